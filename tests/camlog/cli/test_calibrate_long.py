"""``camlog calibrate`` on a long log of a waved board (over a thousand views): every statistic
finite (the signed-rank law of the order and warp choices once overflowed there: p = NaN),
and nothing on the terminal but camlog's own lines, numpy's and OpenCV's warnings made errors.

The log is drawn, not simulated: a chessboard texture mapped through a plumb_bob lens onto
a 320x240 image at each pose of a smooth path (a few ms a frame), so that a thousand
views cost seconds to make.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from replay import CameraInfo, Image, open_writer
from replay.camera import CameraModel

W, H = 320, 240
FOCAL_PX = 260.0
K = np.array([[FOCAL_PX, 0.0, (W - 1) / 2], [0.0, FOCAL_PX, (H - 1) / 2], [0.0, 0.0, 1.0]])
LENS = np.array([-0.25, 0.08, 0.0, 0.0, -0.01])
COLS, ROWS, SQUARE_M = 7, 6, 0.02  # inner corners, as --size counts them
FRAMES = 1_100
RATE_HZ = 30.0
#: board texture pixels per metre (a square is 20 px, about as many as in the image)
TEXTURE_PX_PER_M = 1_000.0


def board_texture() -> tuple[np.ndarray, float]:
    """A white-bordered chessboard of (COLS + 1) x (ROWS + 1) squares, and the texture pixel
    of its first inner corner (on both axes)."""
    square = int(SQUARE_M * TEXTURE_PX_PER_M)
    margin = square
    texture = np.full(((ROWS + 1) * square + 2 * margin, (COLS + 1) * square + 2 * margin),
                      235, np.uint8)
    for r in range(ROWS + 1):
        for c in range(COLS + 1):
            if (r + c) % 2 == 0:
                texture[margin + r * square: margin + (r + 1) * square,
                        margin + c * square: margin + (c + 1) * square] = 20
    return texture, margin + square - 0.5


def poses(count: int) -> list[np.ndarray]:
    """``camera_from_board`` (4, 4) along a smooth path: the board's centre wanders about
    0.32 m in front of the lens and it tilts by up to about 0.6 rad."""
    t = np.arange(count) / RATE_HZ
    centre = [(COLS - 1) * SQUARE_M / 2, (ROWS - 1) * SQUARE_M / 2, 0.0]
    out = []
    for s in t:
        tilt = np.array([0.5 * math.sin(0.53 * s), 0.55 * math.sin(0.37 * s + 1.0),
                         0.3 * math.sin(0.21 * s)])
        rotation, _ = cv2.Rodrigues(tilt)
        position = np.array([0.06 * math.sin(0.41 * s), 0.04 * math.sin(0.29 * s + 0.5),
                             0.32 + 0.04 * math.sin(0.17 * s)])
        pose = np.eye(4)
        pose[:3, :3] = rotation
        pose[:3, 3] = position - rotation @ centre
        out.append(pose)
    return out


def write_log(path: Path) -> None:
    """The waved board seen by the plumb_bob camera, with its camera_info."""
    model = CameraModel(W, H, K, "plumb_bob", LENS)
    us, vs = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    rays = model.pixel_rays(np.column_stack([us.ravel(), vs.ravel()]))
    rays = rays / rays[:, 2:3]  # (x, y, 1) on the normalised plane
    texture, first_px = board_texture()
    texture_from_board = np.array([[TEXTURE_PX_PER_M, 0, first_px],
                                   [0, TEXTURE_PX_PER_M, first_px], [0, 0, 1]])
    stamp0 = 1_700_000_000_000_000_000
    with open_writer(path) as writer:
        for i, pose in enumerate(poses(FRAMES)):
            # normalised plane -> board plane: the inverse of the plane's homography
            normalised_from_board = np.column_stack([pose[:3, 0], pose[:3, 1], pose[:3, 3]])
            mapping = texture_from_board @ np.linalg.inv(normalised_from_board)
            at = rays @ mapping.T
            at = (at[:, :2] / at[:, 2:3]).astype(np.float32).reshape(H, W, 2)
            pixels = cv2.remap(texture, at, None, cv2.INTER_LINEAR, borderValue=128)
            stamp = stamp0 + round(i * 1e9 / RATE_HZ)
            writer.write("/cam/camera_info", CameraInfo(stamp, "cam", W, H, "plumb_bob",
                                                        np.zeros(5), K))
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", pixels))


#: what camlog itself prints for a mono calibration
OWN_LINES = [r"/cam: \d+ views \(.*\), RMS [\d.]+ px", r"  fx [\d.]+ ± [\d.]+  fy .*",
             r"  lens model .*", r"  tangential distortion .*", r"  projection uncertainty .*",
             r"  beyond the boards \(.*\): ±[\d.]+ px \(1 sigma\) — hold the board there to pin it",
             r"  vs the log's /cam/camera_info: .*",
             r"board (held flat|estimated|warp) .*", r"wrote .* in [\d.]+ s"]


@pytest.mark.slow
def test_a_long_log_of_a_waved_board_prints_only_camlogs_lines(tmp_path: Path) -> None:
    log = tmp_path / "waved.mcap"
    write_log(log)
    out = tmp_path / "cal"
    env = {**os.environ, "PYTHONWARNINGS": "error"}
    done = subprocess.run(
        [sys.executable, "-W", "error", "-m", "camlog", "calibrate", str(log), "--camera",
         "/cam", "--size", f"{COLS}x{ROWS}", "--square", str(SQUARE_M), "-o", str(out),
         "--no-progress", "--no-report"], capture_output=True, text=True, env=env, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    lines = done.stdout.splitlines()
    strays = [line for line in lines if not any(re.fullmatch(p, line) for p in OWN_LINES)]
    assert not strays, strays
    assert "nan" not in done.stdout
    camera = json.loads((out / "calibration.json").read_text())["cameras"][0]
    assert camera["used_views"] >= 1_000
    # the order's and the warp's p-values: finite
    assert re.search(r"p = [\d.e-]+", camera["lens_order"]["summary"])
    warp = json.loads((out / "calibration.json").read_text())["board_warp"]
    assert math.isfinite(warp["p_value"]) and 0 <= warp["p_value"] <= 1
    assert "p = nan" not in camera["lens_order"]["summary"]
