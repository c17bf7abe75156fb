"""A recorded fisheye: detected corners of boards up to 95 degrees off axis sit where the
ground truth and cv2.fisheye.projectPoints put them."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from recorder.multiview import plan_multiview_optics
from recorder.optics import plan_optics
from recorder.render import SceneRenderer
from recorder.scenario import load_scenario
from recorder.targets import feature_points_in_target
from replay.camera import CameraModel
from replay.messages import F64

from .logs import Log, transform

NAMESPACE = "/fisheye"
SIZE = 400
K = np.array([[115.0, 0.0, 200.3], [0.0, 115.2, 199.1], [0.0, 0.0, 1.0]])
#: close to an equisolid lens (r = 2 f sin(theta / 2)): 176 degrees across, 300 diagonally
D = [-0.040, 0.0012, -0.0008, 0.0001]
INNER = (5, 4)
SQUARE_M = 0.012
DISTANCE_M = 0.12
#: board name -> (angle of its centre from the optical axis, azimuth in the image), degrees
BOARDS = {"ahead": (0.0, 0.0), "left_50": (50.0, 180.0), "down_75": (75.0, 90.0),
          "corner_95": (95.0, 45.0)}
SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)


def _rpy(rotation: F64) -> list[float]:
    """Roll, pitch, yaw of ``rotation = Rz(yaw) Ry(pitch) Rx(roll)``."""
    return [math.atan2(rotation[2, 1], rotation[2, 2]), -math.asin(rotation[2, 0]),
            math.atan2(rotation[1, 0], rotation[0, 0])]


def _board_table(name: str, angle_deg: float, azimuth_deg: float) -> str:
    """A static board facing the camera, its centre ``DISTANCE_M`` away along the ray."""
    a, z = math.radians(angle_deg), math.radians(azimuth_deg)
    ray = np.array([math.sin(a) * math.cos(z), math.sin(a) * math.sin(z), math.cos(a)])
    helper = np.array([0.0, 0.0, 1.0]) if abs(ray[2]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, ray)
    x /= np.linalg.norm(x)
    rotation = np.column_stack([x, np.cross(ray, x), ray])  # board z: away from the camera
    centre_in_board = np.array([(INNER[0] - 1) / 2, (INNER[1] - 1) / 2, 0.0]) * SQUARE_M
    position = DISTANCE_M * ray - rotation @ centre_in_board
    return f"""
[[targets]]
name = "{name}"
kind = "checkerboard"
inner_corners = [{INNER[0]}, {INNER[1]}]
square_m = {SQUARE_M}
border_squares = 0.5

[targets.motion]
kind = "static"
relative_to = "fisheye"
position_m = {position.tolist()}
rotation_rpy_rad = {_rpy(rotation)}
"""


@pytest.fixture(scope="module")
def spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fisheye") / "fisheye_boards.toml"
    text = f"""
name = "fisheye_boards"
frames = 1

[[cameras]]
name = "fisheye"
namespace = "{NAMESPACE}"
width = {SIZE}
height = {SIZE}
distortion_model = "equidistant"
fx = {K[0, 0]}
fy = {K[1, 1]}
cx = {K[0, 2]}
cy = {K[1, 2]}
distortion = {D}
position_m = [0.0, 0.0, 0.5]
forward = [0.0, 0.0, -1.0]
right = [0.0, 1.0, 0.0]
"""
    path.write_text(text + "".join(_board_table(n, *a) for n, a in BOARDS.items()))
    return path


@pytest.fixture(scope="module")
def log(recording: Callable[..., Log], spec: Path) -> Log:
    return recording(spec)


def test_fisheye_spec_and_record(log: Log, spec: Path) -> None:
    (camera,) = load_scenario(str(spec)).cameras
    assert camera.model.is_fisheye
    (info,) = log.infos(NAMESPACE)
    assert info.distortion_model == "equidistant"
    np.testing.assert_allclose(info.d, D)
    np.testing.assert_allclose(info.k, K)
    entry = log.camera("fisheye")
    assert entry["distortion_model"] == "equidistant"
    assert len(entry["render_views"]) >= 9 and entry["samples_per_side"] >= 2
    (image,) = log.images(NAMESPACE)
    assert image.pixels.shape == (SIZE, SIZE, 3)


def _corners_in_camera(log: Log, board: str) -> F64:
    target = next(t for t in log.scenario["targets"] if t["name"] == board)
    (pose,) = log.truths(NAMESPACE, board)
    camera_from_board = transform(pose)
    corners = np.array(target["corners_in_target"])
    return np.asarray(corners @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])


def _detect_alone(log: Log, board: str, model: CameraModel) -> F64:
    """Corners of one board, the others whited out (each board's outline from the truth)."""
    (image,) = log.images(NAMESPACE)
    gray = cv2.cvtColor(image.pixels, cv2.COLOR_RGB2GRAY)
    corners = _corners_in_camera(log, board)
    cols, rows = INNER
    grid = corners.reshape(rows, cols, 3)
    # the plate's outline: 1.5 squares beyond the outer corners, sampled along its edges
    across, down = grid[0, 1] - grid[0, 0], grid[1, 0] - grid[0, 0]
    first = grid[0, 0] - 1.5 * (across + down)
    width, height = (cols + 2) * across, (rows + 2) * down
    t = np.linspace(0.0, 1.0, 40)[:, None]
    edges = [first + t * width, first + width + t * height,
             first + width + height - t * width, first + height - t * height]
    outline = model.project(np.concatenate(edges))
    mask = np.zeros_like(gray)
    cv2.fillPoly(mask, [np.round(outline).astype(np.int32)], 255)
    alone = np.where(mask > 0, gray, 235).astype(np.uint8)
    found, detected = cv2.findChessboardCorners(alone, (cols, rows),
                                                flags=cv2.CALIB_CB_ADAPTIVE_THRESH)
    assert found, f"{board}: not detected"
    refined = cv2.cornerSubPix(alone, detected, (3, 3), (-1, -1), SUBPIX_CRITERIA)
    return np.asarray(refined, dtype=np.float64).reshape(-1, 2)


@pytest.mark.parametrize("board", sorted(BOARDS))
def test_detected_corners_match_the_projected_truth(log: Log, board: str) -> None:
    (info,) = log.infos(NAMESPACE)
    model = CameraModel.from_camera_info(info)
    corners = _corners_in_camera(log, board)
    centre = corners.mean(axis=0)
    angle_deg = math.degrees(math.acos(centre[2] / np.linalg.norm(centre)))
    assert angle_deg == pytest.approx(BOARDS[board][0], abs=1e-6)
    projected = model.project(corners)
    ahead = corners[:, 2] > 0
    if ahead.any():  # cv2.fisheye.projectPoints is defined in front of the camera
        by_opencv, _ = cv2.fisheye.projectPoints(corners[ahead].reshape(-1, 1, 3), np.zeros(3),
                                                 np.zeros(3), info.k, info.d)
        np.testing.assert_allclose(projected[ahead], by_opencv.reshape(-1, 2), atol=1e-9)
    detected = _detect_alone(log, board, model)
    distances = np.linalg.norm(detected[:, None] - projected[None], axis=2)
    nearest = distances.argmin(axis=1)
    assert len(set(nearest.tolist())) == len(nearest), "two detections matched one corner"
    errors = distances.min(axis=1)
    assert np.median(errors) < 0.15, f"{board}: median {np.median(errors):.3f} px"
    assert errors.max() < 0.3, f"{board}: max {errors.max():.3f} px"


def test_a_board_behind_the_image_plane_is_in_the_image(log: Log) -> None:
    """Past 90 degrees a pinhole has no image; the fisheye shows the board, as the model says."""
    corners = _corners_in_camera(log, "corner_95")
    assert (corners[:, 2] < 0).sum() >= len(corners) // 2


@pytest.mark.slow
def test_views_render_a_pinhole_as_its_direct_render_does(spec: Path) -> None:
    """The multi-view machinery (MuJoCo view intrinsics, atlas, sampling) on a 120-degree
    pinhole camera gives the image of the direct render: corners agree on average within
    0.01 px, one by one within 0.02 px ahead and 0.08 px at 50 degrees (where the pinhole
    stretches squares 2.4-fold and the two anti-aliasing schemes differ most)."""
    scenario = load_scenario(str(spec), {"distortion_model": "plumb_bob", "distortion": [0.0],
                                         "intrinsics": [115.0, 115.0, 199.5, 199.5]})
    (camera,) = scenario.cameras
    poses = [t.motion.world_from_target for t in scenario.targets]
    images = []
    for optics in (plan_optics(camera.model, 2), plan_multiview_optics(camera.model, 2)):
        renderer = SceneRenderer(scenario, [optics])
        try:
            renderer.set_poses(poses)
            images.append(cv2.cvtColor(optics.apply(renderer.render(0)), cv2.COLOR_RGB2GRAY))
        finally:
            renderer.close()
    for board in ("ahead", "left_50"):
        target = next(t for t in scenario.targets if t.name == board)
        world_from_board = target.motion.world_from_target
        camera_from_board = np.linalg.inv(camera.world_from_camera) @ world_from_board
        corners = feature_points_in_target(target) @ camera_from_board[:3, :3].T
        truth = camera.model.project(corners + camera_from_board[:3, 3])
        found = [cv2.cornerSubPix(image, truth.astype(np.float32).reshape(-1, 1, 2), (3, 3),
                                  (-1, -1), SUBPIX_CRITERIA).reshape(-1, 2) for image in images]
        difference = found[1] - found[0]
        assert np.abs(difference.mean(axis=0)).max() < 0.01, board
        assert np.abs(difference).max() < (0.02 if board == "ahead" else 0.08), board
        assert np.abs(found[0] - truth).max() < 0.25, board
