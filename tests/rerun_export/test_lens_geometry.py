"""The pinhole views of distorted cameras are geometrically true, checked from the .rrd alone
with rerun's dataframe API (not camlog's reader): the simulator's true board corners,
carried into the view by the logged ``Transform3D`` chain and imaged by the logged
``Pinhole``, land on the corners OpenCV detects in the logged view image.

Detected corners are each view's OpenCV corners (``findChessboardCorners`` +
``cornerSubPix``, ``CharucoDetector`` for ChArUco) fitted by the homography that maps the
board plane into a pinhole image (``findHomography``): in a true pinhole image the corners
of a plane obey one exactly, and the fit averages the detector's own scatter on rendered
corners (about 0.1 px on ChArUco, whose corners touch the markers). A view that kept any
distortion would bend the corners away from every homography and from the truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import ChunkStore, RrdReader

from replay import open_reader
from replay.geometry import rotation_from_quat_xyzw
from replay.records import Scenario
from tests.recordings import cli

#: the scenarios at 320x240 (their intrinsics halved, as a 640x480 camera binned 2x2)
HALF = {
    "mono_heldout": ("510.7,523.95,165.6,113.85", 45),
    "mono_charuco": ("256.15,256.55,158.85,121.05", 45),
    "mono_fisheye": ("115.85,115.95,160.9,118.55", 60),
}
CAMERAS = {"mono_heldout": ("/heldout_camera", "checkerboard"),
           "mono_charuco": ("/charuco_camera", "charuco"),
           "mono_fisheye": ("/fisheye_camera", "checkerboard")}
#: the fisheye's views at twice the raw size: its 60-degree view otherwise shows the
#: board's squares 6 px wide, too small for a corner detector
SCALE = {"mono_fisheye": "2"}


@dataclass(frozen=True)
class Recorded:
    """A scenario's log and the .rrd ``camlog view`` made of it."""

    scenario: str
    log: Path
    rrd: Path


@pytest.fixture(scope="session", params=list(HALF))
def recorded(request: pytest.FixtureRequest,
             tmp_path_factory: pytest.TempPathFactory) -> Recorded:
    name = request.param
    intrinsics, frames = HALF[name]
    tmp = tmp_path_factory.mktemp(name)
    log, rrd = tmp / f"{name}.mcap", tmp / f"{name}.rrd"
    cli("record", name, "--frames", str(frames), "--resolution", "320x240", "--intrinsics",
        intrinsics, "-o", str(log), "--no-progress")
    cli("view", str(log), "-o", str(rrd), "--no-progress",
        *(("--undistorted-scale", SCALE[name]) if name in SCALE else ()))
    return Recorded(name, log, rrd)


def _store(rrd: Path) -> ChunkStore:
    reader = RrdReader(rrd)
    (entry,) = reader.recordings()
    return reader.stream(store=entry).collect()


def _last(store: ChunkStore, entity: str, component: str) -> object:
    """The last value logged for ``component`` at ``entity`` (None when never)."""
    table = store.reader(index="log_time", contents=entity).to_arrow_table()
    name = f"{entity}:{component}"
    if name not in table.column_names:
        return None
    values = [v for v in table.column(name).to_pylist() if v is not None]
    return values[-1][0] if values else None


def _parent_from_child(store: ChunkStore, entity: str) -> np.ndarray:
    """The ``Transform3D`` logged at ``entity`` (rerun's matrices are column-major)."""
    out = np.eye(4)
    mat3x3, translation = (_last(store, entity, f"Transform3D:{c}")
                           for c in ("mat3x3", "translation"))
    if mat3x3 is not None:
        out[:3, :3] = np.asarray(mat3x3, dtype=np.float64).reshape(3, 3).T
    if translation is not None:
        out[:3, 3] = translation
    return out


def _world_from(store: ChunkStore, entity: str) -> np.ndarray:
    """The transform chain from ``/world`` down to ``entity``."""
    parts = entity.strip("/").split("/")
    out = np.eye(4)
    for depth in range(2, len(parts) + 1):
        out = out @ _parent_from_child(store, "/" + "/".join(parts[:depth]))
    return out


def _images(store: ChunkStore, entity: str) -> dict[int, np.ndarray]:
    """Header stamp -> grey pixels of the images logged at ``entity``."""
    table = store.reader(index="header_stamp", contents=entity).to_arrow_table()
    stamps = table.column("header_stamp").cast(pa.int64()).to_pylist()
    buffers = table.column(f"{entity}:Image:buffer").to_pylist()
    formats = table.column(f"{entity}:Image:format").to_pylist()
    out = {}
    for stamp, buffer, fmt in zip(stamps, buffers, formats, strict=True):
        if buffer is None:
            continue
        width, height = fmt[0]["width"], fmt[0]["height"]
        pixels = np.frombuffer(bytes(buffer[0]), np.uint8).reshape(height, width, -1)
        out[stamp] = cv2.cvtColor(pixels, cv2.COLOR_RGB2GRAY)
    return out


def _detect(gray: np.ndarray, target: str) -> tuple[np.ndarray, np.ndarray | None] | None:
    """OpenCV's corners ``(N, 2)`` and their board ids (None: a whole chessboard, ids found
    by matching) of one image."""
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    if target == "charuco":
        board = cv2.aruco.CharucoBoard((8, 6), 0.011, 0.008,
                                       cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_5X5_100))
        board.setLegacyPattern(False)
        corners, ids, _, _ = cv2.aruco.CharucoDetector(board).detectBoard(gray)
        if corners is None or len(corners) < 8:
            return None
        corners = cv2.cornerSubPix(gray, corners.astype(np.float32), (3, 3), (-1, -1), criteria)
        return corners.reshape(-1, 2).astype(np.float64), ids.ravel()
    found, corners = cv2.findChessboardCorners(gray, (7, 6))
    if not found:
        return None
    corners = cv2.cornerSubPix(gray, corners, (5, 5), (-1, -1), criteria)
    return corners.reshape(-1, 2).astype(np.float64), None


@dataclass(frozen=True)
class Landing:
    """Distances (px) between true corners imaged through the logged view and the corners
    detected in the logged view images; views compared."""

    errors_px: np.ndarray
    views: int


def landing(rec: Recorded, view: str = "undistorted") -> Landing:
    """How far the true corners land from the detected ones in a view of ``rec``."""
    namespace, target = CAMERAS[rec.scenario]
    with open_reader(rec.log) as log:  # the simulator's truth, as it recorded it
        scenario = Scenario.from_message(
            next(m.message for m in log.messages(["/camlog/scenario"])))
        poses = {m.message.stamp_ns: m.message
                 for m in log.messages([f"{namespace}/ground_truth/{target}"])}
    (target_spec,) = [t for t in scenario.targets if t.name == target]
    points_in_target = target_spec.points_in_target()
    (camera,) = [c for c in scenario.cameras if c.namespace == namespace]
    world_from_camera = np.asarray(camera.world_from_camera, dtype=np.float64)

    store = _store(rec.rrd)
    entity = f"/world/{namespace.strip('/')}/{view}"
    view_from_world = np.linalg.inv(_world_from(store, entity))
    k = np.asarray(_last(store, entity, "Pinhole:image_from_camera"),
                   dtype=np.float64).reshape(3, 3).T
    errors, views = [], 0
    for stamp, gray in _images(store, f"{entity}/image").items():
        detected = _detect(gray, target)
        if detected is None:
            continue
        corners, ids = detected
        pose = poses[stamp]
        in_camera = points_in_target @ rotation_from_quat_xyzw(pose.orientation_xyzw).T \
            + pose.position_m
        in_world = in_camera @ world_from_camera[:3, :3].T + world_from_camera[:3, 3]
        in_view = in_world @ view_from_world[:3, :3].T + view_from_world[:3, 3]
        truth = in_view @ k.T
        truth = truth[:, :2] / truth[:, 2:]
        if ids is None:  # a whole chessboard: each detected corner's true corner
            ids = np.linalg.norm(truth[:, None] - corners[None], axis=2).argmin(axis=0)
            assert len(set(ids.tolist())) == len(ids)
        on_board = points_in_target[ids, :2]
        homography, _ = cv2.findHomography(on_board, corners)
        fitted = cv2.perspectiveTransform(on_board.reshape(-1, 1, 2), homography).reshape(-1, 2)
        errors.append(np.linalg.norm(fitted - truth[ids], axis=1))
        views += 1
    return Landing(np.concatenate(errors) if errors else np.zeros(0), views)


@pytest.mark.slow
def test_true_corners_land_on_the_detected_ones(recorded: Recorded) -> None:
    found = landing(recorded)
    assert found.views >= 3, f"{recorded.scenario}: only {found.views} views detected"
    median, worst = float(np.median(found.errors_px)), float(found.errors_px.max())
    assert median <= 0.1, f"{recorded.scenario}: median {median:.3f} px"
    assert worst <= 0.3, f"{recorded.scenario}: max {worst:.3f} px"
