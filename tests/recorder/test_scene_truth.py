"""Rendered pixels agree with the ground truth: checkerboard corners and the red block."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np
import pytest

from recorder.scenario import load_scenario
from recorder.targets import feature_points_in_target
from replay.camera import CameraModel
from replay.messages import F64

from .logs import Log, transform

HFOV_RAD = 0.6
BASELINE_M = 0.02
#: the board is held 0.5 s = 15 frames at 30 Hz: frames 0, 15, 30, 45 show four poses
HOLD_FRAMES = 15
FRAMES = 46
#: fewer pixels than this between the board's outer squares and the image border, and the
#: detector may miss the board: such (deliberately partial) views are not compared
BORDER_PX = 10.0
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)


def test_board_corners_are_row_major_from_the_first_inner_corner() -> None:
    (target,) = load_scenario("mono_checkerboard").targets
    cols, rows = target.inner_corners
    corners = feature_points_in_target(target)
    assert corners.shape == (cols * rows, 3)
    s = target.square_m
    np.testing.assert_allclose(corners[0], [0, 0, 0])
    np.testing.assert_allclose(corners[1] - corners[0], [s, 0, 0])
    np.testing.assert_allclose(corners[cols] - corners[0], [0, s, 0])
    np.testing.assert_allclose(corners[-1], [(cols - 1) * s, (rows - 1) * s, 0])


def _detect(gray: np.ndarray, pattern: tuple[int, int]) -> F64 | None:
    found, corners = cv2.findChessboardCorners(gray, pattern)
    if not found:
        return None
    refined = cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), SUBPIX_CRITERIA)
    return np.asarray(refined, dtype=np.float64).reshape(-1, 2)


def corner_errors(log: Log, frame: int, model: CameraModel | None = None) -> F64 | None:
    """Distance (px) from each detected corner to the nearest true corner projected with
    ``model`` (default: the logged one), or None when the board is not fully in view."""
    (target,) = log.scenario["targets"]
    cols, rows = target["inner_corners"]
    s = target["square_m"]
    corners_in_target = np.array(target["corners_in_target"])
    image = log.images("/simple_camera")[frame]
    info = log.infos("/simple_camera")[frame]
    pose = log.truths("/simple_camera", "checkerboard")[frame]
    assert image.stamp_ns == info.stamp_ns == pose.stamp_ns
    model = model or CameraModel.from_camera_info(info)
    camera_from_board = transform(pose)

    def project(points_in_board: F64) -> F64:
        points = points_in_board @ camera_from_board[:3, :3].T + camera_from_board[:3, 3]
        return model.project(points)

    # the outer corners of the outermost squares (the detector needs whole squares)
    outline = project(np.array([[-s, -s, 0], [cols * s, -s, 0], [cols * s, rows * s, 0],
                                [-s, rows * s, 0]]))
    inside = (
        (outline >= BORDER_PX).all()
        and (outline[:, 0] <= info.width - 1 - BORDER_PX).all()
        and (outline[:, 1] <= info.height - 1 - BORDER_PX).all()
    )
    if not inside:
        return None
    projected = project(corners_in_target)
    detected = _detect(cv2.cvtColor(image.pixels, cv2.COLOR_RGB2GRAY), (cols, rows))
    assert detected is not None, f"frame {frame}: board in view but not detected"
    assert detected.shape == projected.shape
    distances = np.linalg.norm(detected[:, None] - projected[None], axis=2)
    nearest = distances.argmin(axis=1)
    assert len(set(nearest.tolist())) == len(nearest), "two detections matched one corner"
    return distances.min(axis=1)


def errors_over_holds(log: Log, model: CameraModel | None = None) -> tuple[F64, int]:
    """Corner errors of every fully visible hold, and how many holds that was."""
    frames = range(0, FRAMES, HOLD_FRAMES)
    per_frame = [corner_errors(log, frame, model) for frame in frames]
    seen = [e for e in per_frame if e is not None]
    return (np.concatenate(seen) if seen else np.zeros(0)), len(seen)


#: case -> overrides, all at the default supersample 2 (the next-but-one test shows why)
ACCURACY_CASES: dict[str, dict[str, Any]] = {
    "ideal": {},
    "plumb_bob": {"distortion": [-0.2, 0.05, 0.0, 0.0, 0.0]},
    "intrinsics": {"intrinsics": [1000.0, 1060.0, 330.0, 230.0]},
}


@pytest.mark.parametrize("case", sorted(ACCURACY_CASES))
def test_detected_corners_match_the_projected_truth(
    recording: Callable[..., Log], case: str
) -> None:
    log = recording("mono_checkerboard", frames=FRAMES, **ACCURACY_CASES[case])
    assert log.camera("simple_camera")["supersample"] == 2
    (info,) = {(i.width, i.height) for i in log.infos("/simple_camera")}
    assert info == (640, 480)
    errors, views = errors_over_holds(log)
    assert views >= 3
    assert np.median(errors) < 0.1, f"median {np.median(errors):.3f} px"
    assert errors.max() < 0.25, f"max {errors.max():.3f} px over {views} views"


def test_distorted_model_is_the_one_rendered(recording: Callable[..., Log]) -> None:
    """The distortion is really in the pixels: without it, projections miss the corners."""
    log = recording("mono_checkerboard", frames=FRAMES, **ACCURACY_CASES["plumb_bob"])
    info = log.infos("/simple_camera")[0]
    np.testing.assert_allclose(info.d, [-0.2, 0.05, 0, 0, 0])
    fx = 320 / math.tan(HFOV_RAD / 2)
    np.testing.assert_allclose(info.k, [[fx, 0, 319.5], [0, fx, 239.5], [0, 0, 1]])
    pinhole = CameraModel(info.width, info.height, info.k)
    errors, views = errors_over_holds(log, pinhole)
    assert views >= 1
    assert errors.max() > 2 * 0.25  # well beyond the accuracy with the right model


def test_corners_without_supersampling(recording: Callable[..., Log]) -> None:
    """Rendered directly (supersample 1), corners are unbiased but MuJoCo's 8x MSAA
    quantises edge coverage: about twice the scatter, so the worst corner may pass 0.25 px.
    This is why supersample 2 is the default."""
    log = recording("mono_checkerboard", frames=FRAMES, supersample=1)
    assert log.camera("simple_camera")["supersample"] == 1
    errors, views = errors_over_holds(log)
    assert views >= 3
    assert np.median(errors) < 0.15, f"median {np.median(errors):.3f} px"
    assert errors.max() < 0.35, f"max {errors.max():.3f} px"


# --- red_block: the chapter's OpenCV colour example -----------------------------------------

def red_centroid(pixels: np.ndarray) -> F64:
    """Centroid (u, v) of the pixels with R > 10 (G + B)."""
    rgb = pixels.astype(np.int32)
    mask = rgb[..., 0] > 10 * (rgb[..., 1] + rgb[..., 2])
    v, u = np.nonzero(mask)
    assert u.size > 100
    return np.array([u.mean(), v.mean()])


def _clip(polygon: F64, low: F64, high: F64) -> F64:
    """Sutherland-Hodgman clip of a convex polygon (N, 2) to the box [low, high]."""
    for axis in (0, 1):
        for bound, keep in ((low[axis], np.greater_equal), (high[axis], np.less_equal)):
            out = []
            for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
                a_in, b_in = keep(a[axis], bound), keep(b[axis], bound)
                if a_in:
                    out.append(a)
                if a_in != b_in:
                    out.append(a + (b - a) * (bound - a[axis]) / (b[axis] - a[axis]))
            polygon = np.array(out)
    return polygon


def _area_centroid(polygon: F64) -> tuple[float, F64]:
    x, y = polygon[:, 0], polygon[:, 1]
    cross = x * np.roll(y, -1) - np.roll(x, -1) * y
    area = cross.sum() / 2
    centroid = np.array([((x + np.roll(x, -1)) * cross).sum(),
                         ((y + np.roll(y, -1)) * cross).sum()])
    return abs(area), centroid / (6 * area)


def box_image_centroid(model: CameraModel, camera_from_box: F64, size_m: F64) -> F64:
    """Centroid of the image of a box: its faces that look at the camera, projected by the
    (distortion-free) model and clipped to the image, weighted by area."""
    half = np.asarray(size_m) / 2
    camera_in_box = -camera_from_box[:3, :3].T @ camera_from_box[:3, 3]
    total_area, weighted = 0.0, np.zeros(2)
    for axis in range(3):
        for sign in (-1.0, 1.0):
            if sign * (camera_in_box[axis] - sign * half[axis]) <= 0:
                continue  # the face looks away from the camera
            u, w = [a for a in range(3) if a != axis]
            corners = np.zeros((4, 3))
            corners[:, axis] = sign * half[axis]
            corners[:, u] = [-half[u], half[u], half[u], -half[u]]
            corners[:, w] = [-half[w], -half[w], half[w], half[w]]
            points = corners @ camera_from_box[:3, :3].T + camera_from_box[:3, 3]
            polygon = _clip(model.project(points), np.array([-0.5, -0.5]),
                            np.array([model.width - 0.5, model.height - 0.5]))
            area, centroid = _area_centroid(polygon)
            total_area += area
            weighted += area * centroid
    return weighted / total_area


@pytest.fixture(scope="module")
def red_block(recording: Callable[..., Log]) -> Log:
    return recording("red_block", frames=1)


def test_red_block_is_centred_in_the_left_image(red_block: Log) -> None:
    (image,) = red_block.images("/stereo_camera/left")
    assert image.pixels.shape == (480, 640, 3)
    np.testing.assert_allclose(red_centroid(image.pixels), [319.5, 239.5], atol=0.5)


def test_red_block_disparity_in_the_right_image(red_block: Log) -> None:
    (left,) = red_block.images("/stereo_camera/left")
    (right,) = red_block.images("/stereo_camera/right")
    fx = 320 / math.tan(HFOV_RAD / 2)
    shift = red_centroid(left.pixels) - red_centroid(right.pixels)
    # the chapter's estimate (a point 0.1 m away), up to the box depth and the image border
    assert shift[0] == pytest.approx(fx * BASELINE_M / 0.1, rel=0.05)
    assert abs(shift[1]) < 0.5
    # exactly: the visible faces of the box, projected and clipped
    (target,) = red_block.scenario["targets"]
    (info,) = red_block.infos("/stereo_camera/right")
    (pose,) = red_block.truths("/stereo_camera/right", "red_block")
    expected = box_image_centroid(CameraModel.from_camera_info(info), transform(pose),
                                  np.array(target["size_m"]))
    np.testing.assert_allclose(red_centroid(right.pixels), expected, atol=0.5)


def _wall_shift_px(model: CameraModel, camera_from_board: F64, points: F64,
                   wall_m: float) -> F64:
    """Where corners would move ``(N, 2)`` if each dark square had side walls ``wall_m``
    high behind its face: a ray passing beside an edge at an angle meets the wall, which
    moves the edge against the ray's sideways travel by ``wall_m`` times the tangent of the
    angle on one of the junction's two halves (half that on average)."""
    rotation, translation = camera_from_board[:3, :3], camera_from_board[:3, 3]
    in_camera = points @ rotation.T + translation
    ray_in_board = (in_camera / np.linalg.norm(in_camera, axis=1, keepdims=True)) @ rotation
    shift = np.zeros_like(points)
    shift[:, :2] = -(wall_m / 2) * ray_in_board[:, :2] / ray_in_board[:, 2:]
    return model.project((points + shift) @ rotation.T + translation) - model.project(in_camera)


def test_rendered_corners_show_no_side_walls(recording: Callable[..., Log]) -> None:
    """Seen at an angle, the board's features put their corners where the truth says: the
    recorder's corners differ from those of an exact render of the same pose by noise, not
    by the pattern side walls 20 um high would leave (0.02 px towards the image border)."""
    from benchmarks.ideal_board import ideal_image
    from processors.calibration.board import Board
    from processors.calibration.detect import track_chessboard

    log = recording("mono_checkerboard", frames=FRAMES)
    (target,) = log.scenario["targets"]
    board = Board(*target["inner_corners"], target["square_m"])
    points = np.array(target["corners_in_target"])
    measured, pattern = [], []
    for frame in range(0, FRAMES, HOLD_FRAMES):
        if corner_errors(log, frame) is None:  # not fully in view
            continue
        info = log.infos("/simple_camera")[frame]
        model = CameraModel.from_camera_info(info)
        camera_from_board = transform(log.truths("/simple_camera", "checkerboard")[frame])
        true_px = model.project(points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
        gray = cv2.cvtColor(log.images("/simple_camera")[frame].pixels, cv2.COLOR_RGB2GRAY)
        found = [track_chessboard(image, true_px, board) for image in
                 (gray, ideal_image(model, camera_from_board, board))]
        assert all(f is not None for f in found)
        rendered, exact = (f.corners_px for f in found if f is not None)
        for corners in (rendered, exact):  # in the board's order
            if np.linalg.norm(corners[0] - true_px[0]) > 1.0:
                corners[:] = corners[::-1]
        measured.append((rendered - exact).ravel())
        pattern.append(_wall_shift_px(model, camera_from_board, points, 20e-6).ravel())
    assert len(measured) >= 3
    difference, walls = np.concatenate(measured), np.concatenate(pattern)
    assert np.sqrt(np.mean(walls ** 2)) > 0.005  # the views are oblique enough to show walls
    slope = float(difference @ walls / (walls @ walls))
    assert abs(slope) < 0.35, f"corners move as {slope:.2f} x 20 um walls would move them"
