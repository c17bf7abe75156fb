"""ChArUco and circle-grid targets: OpenCV's layouts built exactly, found by OpenCV's
detectors where the truth in the log says."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from recorder.errors import ScenarioError
from recorder.scenario import load_scenario, parse_scenario
from recorder.targets import (
    black_rectangles,
    cell_rectangles,
    charuco_board,
    feature_points_in_target,
    markers_in_target,
)
from replay.camera import CameraModel
from replay.messages import F64

from .logs import Log, transform

NAMESPACE = "/cam"
CAMERA = f"""
name = "targets"
frames = 1

[[cameras]]
name = "cam"
namespace = "{NAMESPACE}"
width = 640
height = 480
hfov_rad = 0.9
position_m = [0.0, 0.0, 0.5]
forward = [0.0, 0.0, -1.0]
right = [0.0, 1.0, 0.0]
"""
BOARDS = """
[[targets]]
name = "charuco"
kind = "charuco"
squares = [6, 5]
square_m = 0.012
marker_m = 0.009

[targets.motion]
kind = "static"
relative_to = "cam"
position_m = [-0.095, -0.06, 0.25]
rotation_rpy_rad = [0.2, 0.1, 0.05]

[[targets]]
name = "circles"
kind = "circles"
circles = [5, 4]
spacing_m = 0.012

[targets.motion]
kind = "static"
relative_to = "cam"
position_m = [0.03, -0.06, 0.25]
rotation_rpy_rad = [-0.1, 0.25, 0.0]

[[targets]]
name = "acircles"
kind = "acircles"
circles = [4, 7]
spacing_m = 0.007

[targets.motion]
kind = "static"
relative_to = "cam"
position_m = [-0.01, 0.035, 0.25]
rotation_rpy_rad = [0.0, -0.2, 0.3]
"""
#: a ChArUco board a third out of the image, past its left border
PARTIAL = """
[[targets]]
name = "charuco"
kind = "charuco"
squares = [8, 6]
square_m = 0.012
marker_m = 0.009
dictionary = "DICT_4X4_50"

[targets.motion]
kind = "static"
relative_to = "cam"
position_m = [-0.155, -0.03, 0.25]
rotation_rpy_rad = [0.0, 0.15, 0.1]
"""


def _spec(tmp_path_factory: pytest.TempPathFactory, name: str, text: str) -> Path:
    path = tmp_path_factory.mktemp("targets") / f"{name}.toml"
    path.write_text(CAMERA + text)
    return path


@pytest.fixture(scope="module")
def boards(recording: Callable[..., Log], tmp_path_factory: pytest.TempPathFactory) -> Log:
    return recording(_spec(tmp_path_factory, "boards", BOARDS))


@pytest.fixture(scope="module")
def partial(recording: Callable[..., Log], tmp_path_factory: pytest.TempPathFactory) -> Log:
    return recording(_spec(tmp_path_factory, "partial", PARTIAL))


# --- layouts, without rendering ---------------------------------------------------------

def _target(kind: str, **fields: Any) -> Any:
    table = {"name": "t", "kind": kind, **fields}
    raw: dict[str, Any] = {"name": "s", "cameras": [{"name": "c", "position_m": [0, 0, 1],
                                                      "forward": [0, 0, -1], "right": [1, 0, 0]}],
                           "targets": [table]}
    return parse_scenario(raw, "test").targets[0]


def test_charuco_black_areas_are_opencvs_board_image() -> None:
    """Rasterised at 10 px per mm, the black squares and marker cells are the pixels that
    OpenCV's CharucoBoard.generateImage draws black."""
    target = _target("charuco", squares=[5, 4], square_m=0.01, marker_m=0.007,
                     dictionary="DICT_5X5_100")
    px_per_m = 10_000
    width, height = 5 * 100, 4 * 100
    image = np.full((height, width), 255, np.uint8)
    for x0, x1, y0, y1 in black_rectangles(target):
        rows = slice(round(y0 * px_per_m), round(y1 * px_per_m))
        image[rows, round(x0 * px_per_m):round(x1 * px_per_m)] = 0
    expected = charuco_board(target).generateImage((width, height), marginSize=0, borderBits=1)
    assert (image != expected).mean() < 1e-3


def test_charuco_points_are_opencvs() -> None:
    target = _target("charuco", squares=[6, 5], square_m=0.012, marker_m=0.009,
                     dictionary="DICT_6X6_250")
    board = cv2.aruco.CharucoBoard((6, 5), 0.012, 0.009,
                                   cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_6X6_250))
    np.testing.assert_allclose(feature_points_in_target(target), board.getChessboardCorners())
    ids, corners = markers_in_target(target)
    np.testing.assert_array_equal(ids, np.asarray(board.getIds()).ravel())
    np.testing.assert_allclose(corners, np.asarray(board.getObjPoints()))
    assert len(ids) == 15 and feature_points_in_target(target).shape == (20, 3)


def test_circle_grids_follow_opencvs_layouts() -> None:
    symmetric = feature_points_in_target(_target("circles", circles=[3, 2], spacing_m=0.02))
    np.testing.assert_allclose(symmetric[:, :2], [[0, 0], [0.02, 0], [0.04, 0],
                                                  [0, 0.02], [0.02, 0.02], [0.04, 0.02]])
    # OpenCV's calibration sample: ((2 j + i % 2) s, i s) for row i, column j
    asymmetric = feature_points_in_target(_target("acircles", circles=[2, 3], spacing_m=0.01))
    np.testing.assert_allclose(asymmetric[:, :2], [[0, 0], [0.02, 0], [0.01, 0.01], [0.03, 0.01],
                                                   [0, 0.02], [0.02, 0.02]])
    assert (asymmetric[:, 2] == 0).all()


@pytest.mark.parametrize(("fields", "needle"), [
    ({"kind": "charuco", "dictionary": "DICT_9X9_1"}, "unknown ArUco dictionary"),
    ({"kind": "charuco", "square_m": 0.01, "marker_m": 0.012}, "marker_m"),
    ({"kind": "charuco", "squares": [12, 12], "dictionary": "DICT_4X4_50"}, "too few"),
    ({"kind": "circles", "spacing_m": 0.01, "diameter_m": 0.012}, "overlap"),
    ({"kind": "acircles", "squares": [4, 11]}, "unknown key"),
])
def test_bad_target_specs(fields: dict[str, Any], needle: str) -> None:
    with pytest.raises(ScenarioError, match=needle) as info:
        _target(**fields)
    assert "targets[0]" in str(info.value)


def test_marker_cells_merge_into_rectangles() -> None:
    """Merged runs cover exactly the black cells, each once."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        black = rng.uniform(size=(7, 7)) < 0.5
        covered = np.zeros((7, 7), int)
        for r0, c0, r1, c1 in cell_rectangles(black):
            covered[r0:r1, c0:c1] += 1
        np.testing.assert_array_equal(covered, black.astype(int))


# --- rendered and detected ----------------------------------------------------------------

def _project(log: Log, name: str, points: F64) -> F64:
    (info,) = log.infos(NAMESPACE)
    (pose,) = log.truths(NAMESPACE, name)
    camera_from_target = transform(pose)
    in_camera = np.asarray(points) @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
    return CameraModel.from_camera_info(info).project(in_camera)


def _gray(log: Log) -> np.ndarray:
    (image,) = log.images(NAMESPACE)
    return np.asarray(cv2.cvtColor(image.pixels, cv2.COLOR_RGB2GRAY))


def _detect_charuco(log: Log) -> tuple[F64, np.ndarray, np.ndarray]:
    """ChArUco corners (N, 2), their ids (N,) and the marker ids found."""
    (target,) = (t for t in log.scenario["targets"] if t["kind"] == "charuco")
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, target["dictionary"]))
    board = cv2.aruco.CharucoBoard(tuple(target["squares"]), target["square_m"],
                                   target["marker_m"], dictionary)
    corners, ids, _, marker_ids = cv2.aruco.CharucoDetector(board).detectBoard(_gray(log))
    assert ids is not None and marker_ids is not None, "no ChArUco corners found"
    return (np.asarray(corners, dtype=np.float64).reshape(-1, 2), np.asarray(ids).ravel(),
            np.asarray(marker_ids).ravel())


def test_charuco_is_found_where_the_truth_says(boards: Log) -> None:
    (target,) = (t for t in boards.scenario["targets"] if t["kind"] == "charuco")
    assert target["dictionary"] == "DICT_5X5_100"  # the default
    assert target["corner_ids"] == list(range(20))
    corners, ids, marker_ids = _detect_charuco(boards)
    assert sorted(ids.tolist()) == target["corner_ids"]
    assert sorted(marker_ids.tolist()) == sorted(target["marker_ids"])
    truth = _project(boards, "charuco", np.array(target["corners_in_target"]))
    errors = np.linalg.norm(corners - truth[ids], axis=1)
    assert np.median(errors) < 0.15 and errors.max() < 0.3, errors


def test_partly_visible_charuco_gives_the_corners_in_view(partial: Log) -> None:
    (target,) = partial.scenario["targets"]
    truth = _project(partial, "charuco", np.array(target["corners_in_target"]))
    inside = (truth[:, 0] > 8) & (truth[:, 0] < 631) & (truth[:, 1] > 8) & (truth[:, 1] < 471)
    assert 0.4 < inside.mean() < 0.9  # the board is cut by the border
    corners, ids, marker_ids = _detect_charuco(partial)
    # corners next to the border need both neighbouring markers whole, so a few go missing
    assert len(ids) >= max(6, 0.6 * inside.sum())
    assert set(ids.tolist()) <= set(np.flatnonzero(inside).tolist())
    assert set(marker_ids.tolist()) < set(target["marker_ids"])
    errors = np.linalg.norm(corners - truth[ids], axis=1)
    assert np.median(errors) < 0.15 and errors.max() < 0.3, errors


@pytest.mark.parametrize("name", ["circles", "acircles"])
def test_circle_grids_are_found_where_the_truth_says(boards: Log, name: str) -> None:
    (target,) = (t for t in boards.scenario["targets"] if t["name"] == name)
    assert target["asymmetric"] == (name == "acircles")
    truth = _project(boards, name, np.array(target["centres_in_target"]))
    # the other boards whited out: findCirclesGrid looks for one grid
    gray = _gray(boards)
    mask = np.zeros_like(gray)
    cv2.fillPoly(mask, [cv2.convexHull(truth.astype(np.float32)).astype(np.int32)], 255)
    alone = np.where(cv2.dilate(mask, np.ones((25, 25), np.uint8)) > 0, gray, 240)
    flags = cv2.CALIB_CB_ASYMMETRIC_GRID if target["asymmetric"] else cv2.CALIB_CB_SYMMETRIC_GRID
    found, centres = cv2.findCirclesGrid(alone.astype(np.uint8), tuple(target["circles"]),
                                         flags=flags)
    assert found
    errors = np.linalg.norm(np.asarray(centres).reshape(-1, 2) - truth, axis=1)
    # blob centroids of tilted disks sit a little off the projected centres (perspective)
    assert np.median(errors) < 0.1 and errors.max() < 0.2, errors


def test_scenario_record_holds_the_target_geometry(boards: Log) -> None:
    by_name = {t["name"]: t for t in boards.scenario["targets"]}
    spec = load_scenario(str(boards.scenario["source"]))
    for target in spec.targets:
        entry = by_name[target.name]
        key = "centres_in_target" if target.kind.endswith("circles") else "corners_in_target"
        np.testing.assert_allclose(entry[key], feature_points_in_target(target))
    assert len(by_name["charuco"]["marker_corners_in_target"]) == len(
        by_name["charuco"]["marker_ids"])
