"""A real rerun viewer (headless, Mesa's software Vulkan) draws a tiny ``view`` recording:
the camera view's screenshot shows the logged image, not a blank panel."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from benchmarks.screenshots import Viewer, vulkan_driver
from replay import Image, open_writer
from replay.camera import CameraModel
from rerun_export import view_logs

T0 = 1_700_000_000_000_000_000


@pytest.mark.slow
def test_the_viewer_draws_the_camera_image(tmp_path: Path) -> None:
    missing = vulkan_driver()
    if missing:
        pytest.skip(missing)
    log = tmp_path / "tiny.mcap"
    with open_writer(log) as writer:
        for i in range(4):
            stamp = T0 + i * 100_000_000
            pixels = np.full((48, 64, 3), 40, np.uint8)
            pixels[10:38, 16 + i:48 + i] = (230, 20, 20)  # a red block, moving right
            writer.write("/cam/image_raw", Image(stamp, "cam", "rgb8", pixels),
                         log_time_ns=stamp)
            writer.write("/cam/camera_info",
                         CameraModel.ideal(64, 48, 0.6).camera_info(stamp_ns=stamp,
                                                                    frame_id="cam"),
                         log_time_ns=stamp)
    rrd = tmp_path / "tiny.rrd"
    view_logs([log], output=rrd, progress=False)
    with Viewer(tmp_path / "viewer_home") as viewer:
        whole = viewer.screenshot(rrd, tmp_path / "whole.png", settle_s=2.0)
        camera = viewer.screenshot(rrd, tmp_path / "camera.png", settle_s=2.0,
                                   view_origin="/world/cam")
    shot = cv2.imread(str(whole), cv2.IMREAD_COLOR)
    assert shot is not None and shot.shape[0] >= 400 and shot.shape[1] >= 600
    assert float(shot.std()) > 10  # the viewer's panels, not one flat colour
    view = cv2.imread(str(camera), cv2.IMREAD_COLOR).astype(int)
    blue, green, red = view[..., 0], view[..., 1], view[..., 2]
    block = (red > 180) & (green < 80) & (blue < 80)
    # the block covers 28x32 of the 64x48 image: about 30 % of the image's pixels in the
    # view, however large the viewer draws it
    assert block.sum() > 0.05 * view.shape[0] * view.shape[1], block.sum()
