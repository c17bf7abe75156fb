"""A real rerun viewer (headless, Mesa's software Vulkan) draws tiny ``view`` recordings:
the camera view's screenshot shows the logged image, not a blank panel; a distorted camera's
3D points, projected by the viewer through its undistorted view, land where its lens saw
them."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from benchmarks.screenshots import Viewer, vulkan_driver
from replay import Image, open_writer
from replay.camera import CameraModel
from replay.records import ViewResiduals
from rerun_export import LoggerOptions, view_logs

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


@pytest.mark.slow
def test_the_board_lands_on_the_undistorted_image_in_the_viewer(tmp_path: Path) -> None:
    """A strongly distorted camera (plumb_bob k1 = -0.35) sees white discs at 3D points;
    the calibration record puts those points in 3D. The viewer's own projection of them
    through the undistorted view's Pinhole lands on the discs of the undistorted image."""
    missing = vulkan_driver()
    if missing:
        pytest.skip(missing)
    width, height = 160, 120
    k = np.array([[150.0, 0, 79.5], [0, 150.0, 59.5], [0, 0, 1]])
    model = CameraModel(width, height, k, "plumb_bob", np.array([-0.35, 0.12, 0, 0, 0]))
    xs, ys = np.meshgrid(np.linspace(-0.45, 0.45, 5), np.linspace(-0.3, 0.3, 4))
    points = np.column_stack([xs.ravel(), ys.ravel(), np.ones(xs.size)])
    raw_px = model.project(points)
    pixels = np.zeros((height, width, 3), np.uint8)
    for u, v in raw_px:
        cv2.circle(pixels, (round(u * 16), round(v * 16)), 5 * 16, (255, 255, 255), -1,
                   cv2.LINE_AA, shift=4)
    log = tmp_path / "lens.mcap"
    with open_writer(log) as writer:
        for i in range(3):
            stamp = T0 + i * 100_000_000
            writer.write("/cam/image_raw", Image(stamp, "cam", "rgb8", pixels),
                         log_time_ns=stamp)
            writer.write("/cam/camera_info", model.camera_info(stamp_ns=stamp, frame_id="cam"),
                         log_time_ns=stamp)
            writer.write("/cam/calibration/residuals", ViewResiduals(
                stamp, "cam", 0.0, raw_px, np.zeros_like(raw_px),
                corners_in_camera_m=points).to_message(), log_time_ns=stamp)
    rrd = tmp_path / "lens.rrd"
    view_logs([log], output=rrd, progress=False, options=LoggerOptions(undistorted_scale=1.0))
    with Viewer(tmp_path / "viewer_home") as viewer:
        shot = viewer.screenshot(rrd, tmp_path / "undistorted.png", settle_s=2.0,
                                 view_origin="/world/cam/undistorted")
    view = cv2.imread(str(shot), cv2.IMREAD_COLOR).astype(int)
    blue, green, red = view[..., 0], view[..., 1], view[..., 2]
    marks = ((green > 150) & (red < 130) & (blue < 130)).astype(np.uint8)
    count, _, stats, centres = cv2.connectedComponentsWithStats(marks)
    white = (view.min(axis=2) > 200).astype(np.uint8)
    landed = 0
    for index in range(1, count):
        x, y = (round(c) for c in centres[index])
        size = max(stats[index, cv2.CC_STAT_WIDTH], stats[index, cv2.CC_STAT_HEIGHT])
        ring = np.zeros_like(white)
        cv2.circle(ring, (x, y), size + 3, 1, 2)
        landed += white[ring > 0].mean() > 0.8
    assert count - 1 == len(points), f"{count - 1} marks for {len(points)} points"
    assert landed == len(points), f"{landed} of {len(points)} marks on their disc"
