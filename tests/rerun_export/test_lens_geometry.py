"""The pinhole views of distorted cameras are geometrically true, checked from the .rrd alone
with rerun's dataframe API (not camlog's reader): the simulator's true board corners,
carried into the view by the logged ``Transform3D`` chain and imaged by the logged
``Pinhole``, land on the corners OpenCV detects in the logged view image.

Detected corners are each view's OpenCV corners (``findChessboardCornersSB`` +
``cornerSubPix``, ``CharucoDetector`` for ChArUco) fitted by the homography that maps the
board plane into a pinhole image (``findHomography``): in a true pinhole image the corners
of a plane obey one exactly, and the fit averages the detector's own scatter on rendered
corners (about 0.1 px on ChArUco, whose corners touch the markers). A view that kept any
distortion would bend the corners away from every homography and from the truth.
"""

from __future__ import annotations

import bisect
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
from tests.recordings import SCENARIOS, cli


@dataclass(frozen=True)
class Case:
    """How a scenario is recorded for the test: its camera and target, the image size and
    intrinsics (halved: a 640x480 camera binned 2x2), frames, what of the scenario changes,
    the views' scale and the pinhole views checked."""

    camera: str
    target: str
    resolution: str
    intrinsics: str | None
    frames: int
    changes: tuple[tuple[str, str], ...] = ()
    scale: str = "1"
    views: tuple[str, ...] = ("undistorted",)


#: poses held 0.1 s, so that a few frames show several of them
SHORT_HOLDS = (("hold_s = 0.5", "hold_s = 0.1"), ("hold_s = 0.25", "hold_s = 0.1"))
CASES = {
    "mono_heldout": Case("/heldout_camera", "checkerboard", "320x240",
                         "510.7,523.95,165.6,113.85", 15, SHORT_HOLDS),
    # at full size: OpenCV's ChArUco corners scatter too much on a binned image
    "mono_charuco": Case("/charuco_camera", "charuco", "640x480", None, 12, SHORT_HOLDS),
    # boards drawn below the camera (aimed at the image, the planner would spend minutes on
    # its corners, 83 degrees off axis, that no board within 60 degrees reaches), one pose a
    # frame and a half, up to 49 degrees off axis; the views at twice the raw size (else the
    # board's squares are 6 px wide)
    "mono_fisheye": Case("/fisheye_camera", "checkerboard", "320x240",
                         "115.85,115.95,160.9,118.55", 12,
                         (("hold_s = 0.5", "hold_s = 0.05"),
                          ("max_tilt_rad = 0.7", "max_tilt_rad = 0.5"),
                          ('aim = "image"', 'aim = "world"\ncenter_m = [0.0, 0.0, 0.0]\n'
                                            'xy_range_m = 0.07\nz_range_m = [0.37, 0.41]')),
                         scale="2", views=("undistorted", "wide")),
}


@dataclass(frozen=True)
class Recorded:
    """A scenario's log and the .rrd files ``camlog view`` made of it, with its views and
    with ``--no-undistort``."""

    scenario: str
    log: Path
    rrd: Path
    plain_rrd: Path


@pytest.fixture(scope="module", params=list(CASES))
def recorded(request: pytest.FixtureRequest,
             tmp_path_factory: pytest.TempPathFactory) -> Recorded:
    name = request.param
    case = CASES[name]
    tmp = tmp_path_factory.mktemp(name)
    spec = (SCENARIOS / f"{name}.toml").read_text()
    for old, new in case.changes:
        spec = spec.replace(old, new)
    (tmp / "spec.toml").write_text(spec)
    log, rrd, plain = tmp / f"{name}.mcap", tmp / f"{name}.rrd", tmp / "plain.rrd"
    cli("record", str(tmp / "spec.toml"), "--frames", str(case.frames), "--resolution",
        case.resolution, *(("--intrinsics", case.intrinsics) if case.intrinsics else ()),
        "-o", str(log), "--no-progress")
    cli("view", str(log), "-o", str(rrd), "--no-progress", "--undistorted-scale", case.scale)
    cli("view", str(log), "-o", str(plain), "--no-progress", "--no-undistort")
    return Recorded(name, log, rrd, plain)


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
    # the sector-based detector finds the grid (the classic one can misplace a corner on a
    # board that is strongly foreshortened), cornerSubPix refines it (closer on rendered
    # corners than the sector detector's own sub-pixel fit)
    found, corners = cv2.findChessboardCornersSB(
        gray, (7, 6), flags=cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE)
    if not found:
        return None
    # a window of about a third of a square: a wider one reaches the next corners on small
    # squares (the fisheye's wide view)
    spacing = float(np.median(np.linalg.norm(np.diff(corners.reshape(6, 7, 2), axis=1), axis=2)))
    half = int(np.clip(spacing // 3, 2, 5))
    corners = cv2.cornerSubPix(gray, corners.astype(np.float32), (half, half), (-1, -1),
                               criteria)
    return corners.reshape(-1, 2).astype(np.float64), None


@dataclass(frozen=True)
class Landing:
    """Distances (px) between true corners imaged through the logged view and the corners
    detected in the logged view images; views compared."""

    errors_px: np.ndarray
    views: int


def landing(rec: Recorded, rrd: Path, pinhole: str) -> Landing:
    """How far the true corners land from the detected ones in the images under the
    ``Pinhole`` entity ``pinhole`` (a path under the camera's) of ``rrd``."""
    case = CASES[rec.scenario]
    with open_reader(rec.log) as log:  # the simulator's truth, as it recorded it
        scenario = Scenario.from_message(
            next(m.message for m in log.messages(["/camlog/scenario"])))
        poses = {m.message.stamp_ns: m.message
                 for m in log.messages([f"{case.camera}/ground_truth/{case.target}"])}
    (target,) = [t for t in scenario.targets if t.name == case.target]
    points_in_target = target.points_in_target()
    (camera,) = [c for c in scenario.cameras if c.namespace == case.camera]
    world_from_camera = np.asarray(camera.world_from_camera, dtype=np.float64)

    store = _store(rrd)
    entity = f"/world/{case.camera.strip('/')}{pinhole}"
    view_from_world = np.linalg.inv(_world_from(store, entity))
    k = np.asarray(_last(store, entity, "Pinhole:image_from_camera"),
                   dtype=np.float64).reshape(3, 3).T
    errors, views = [], 0
    for stamp, gray in _images(store, f"{entity}/image").items():
        detected = _detect(gray, case.target)
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
        if ids is None:  # a whole chessboard, in board order from one end or the other
            ids = min((np.arange(len(corners)), np.arange(len(corners))[::-1]),
                      key=lambda order: float(np.linalg.norm(truth[order] - corners,
                                                             axis=1).mean()))
        on_board = points_in_target[ids, :2]
        homography, _ = cv2.findHomography(on_board, corners)
        fitted = cv2.perspectiveTransform(on_board.reshape(-1, 1, 2), homography).reshape(-1, 2)
        errors.append(np.linalg.norm(fitted - truth[ids], axis=1))
        views += 1
    return Landing(np.concatenate(errors) if errors else np.zeros(0), views)


@pytest.mark.slow
def test_true_corners_land_on_the_detected_ones(recorded: Recorded) -> None:
    """In every pinhole view of the camera (a fisheye's wider second view too)."""
    for view in CASES[recorded.scenario].views:
        found = landing(recorded, recorded.rrd, f"/{view}")
        where = f"{recorded.scenario} ({view})"
        assert found.views >= 3, f"{where}: only {found.views} views detected"
        median, worst = float(np.median(found.errors_px)), float(found.errors_px.max())
        assert median <= 0.1, f"{where}: median {median:.3f} px"
        assert worst <= 0.3, f"{where}: max {worst:.3f} px"


def _by_stamp(store: ChunkStore, entity: str, component: str) -> dict[int, object]:
    """Header stamp -> the values (a list) of ``component`` logged at ``entity`` then."""
    table = store.reader(index="header_stamp", contents=entity).to_arrow_table()
    name = f"{entity}:{component}"
    if name not in table.column_names:
        return {}
    stamps = table.column("header_stamp").cast(pa.int64()).to_pylist()
    return {stamp: value for stamp, value in zip(stamps, table.column(name).to_pylist(),
                                                  strict=True) if value is not None}


@pytest.mark.slow
def test_each_view_s_image_plane_is_at_the_board_it_shows(recorded: Recorded) -> None:
    """Wherever the simulator's board is drawn in 3D, every view's image plane is at its
    median depth (a wider view's at its own multiple of it), so that the board's points lie
    on the view's image in 3D."""
    from rerun_export.lens import VIEW_PLANE_DEPTHS

    case = CASES[recorded.scenario]
    store = _store(recorded.rrd)
    camera = f"/world/{case.camera.strip('/')}"
    boards = _by_stamp(store, f"{camera}/ground_truth/{case.target}", "Points3D:positions")
    assert len(boards) >= 3
    for view in case.views:
        planes = sorted(_by_stamp(store, f"{camera}/{view}",
                                  "Pinhole:image_plane_distance").items())
        stamps = [stamp for stamp, _ in planes]
        for stamp, positions in boards.items():
            # the latest plane at the board's time (a board held still is not logged again)
            at = bisect.bisect_right(stamps, stamp) - 1
            assert at >= 0, (view, stamp)
            depth = float(np.median(np.asarray(positions, dtype=np.float64)[:, 2]))
            assert planes[at][1][0] == pytest.approx(
                depth * VIEW_PLANE_DEPTHS.get(view, 1.0), rel=1e-5), (view, stamp)


@pytest.mark.slow
def test_the_raw_image_under_a_pinhole_of_k_misses_by_pixels(recorded: Recorded) -> None:
    """What rerun shows without the views: the raw image under a Pinhole of its K, whose
    lens bends the board away from where the pinhole puts its corners."""
    plain = landing(recorded, recorded.plain_rrd, "")
    assert plain.views >= 1
    assert float(plain.errors_px.max()) > 1.0, recorded.scenario


@pytest.fixture(scope="module")
def stereo_calibration_rrd(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """``stereo_checkerboard`` at 320x240, poses held 0.1 s, calibrated as a pair, and the
    view of its calibration.mcap (the log, the .rrd)."""
    tmp = tmp_path_factory.mktemp("stereo_lens")
    spec = (SCENARIOS / "stereo_checkerboard.toml").read_text().replace("hold_s = 0.5",
                                                                        "hold_s = 0.1")
    (tmp / "spec.toml").write_text(spec)
    log = tmp / "stereo.mcap"
    cli("record", str(tmp / "spec.toml"), "--frames", "90", "--resolution", "320x240",
        "-o", str(log), "--no-progress")
    cli("calibrate", str(log), "--left", "/stereo_camera/left", "--right",
        "/stereo_camera/right", "--size", "7x6", "--square", "0.01", "-o", str(tmp / "cal"),
        "--no-progress")
    rrd = tmp / "stereo.rrd"
    cli("view", str(tmp / "cal" / "calibration.mcap"), "-o", str(rrd), "--no-progress",
        "--undistorted-scale", "1")
    return log, rrd


@pytest.mark.slow
def test_a_rectified_pair_s_views_share_their_rows(
        stereo_calibration_rrd: tuple[Path, Path]) -> None:
    """Each camera of a calibrated pair is shown through its rectified pinhole (P, turned
    by R): a true board corner, carried into both views by the logged transforms, images
    on the same row of both, and where the pair's baseline puts it along the row."""
    log, rrd = stereo_calibration_rrd
    store = _store(rrd)
    with open_reader(log) as reader:
        scenario = Scenario.from_message(
            next(m.message for m in reader.messages(["/camlog/scenario"])))
        poses = [m.message for m in reader.messages(
            ["/stereo_camera/left/ground_truth/checkerboard"])]
    (target,) = scenario.targets
    (left,) = [c for c in scenario.cameras if c.namespace == "/stereo_camera/left"]
    world_from_left = np.asarray(left.world_from_camera, dtype=np.float64)
    pixels = {}
    for side in ("left", "right"):
        entity = f"/world/stereo_camera/{side}/rectified"
        view_from_world = np.linalg.inv(_world_from(store, entity))
        k = np.asarray(_last(store, entity, "Pinhole:image_from_camera"),
                       dtype=np.float64).reshape(3, 3).T
        found = []
        for pose in poses[::5]:
            in_left = target.points_in_target() @ rotation_from_quat_xyzw(
                pose.orientation_xyzw).T + pose.position_m
            in_world = in_left @ world_from_left[:3, :3].T + world_from_left[:3, 3]
            in_view = in_world @ view_from_world[:3, :3].T + view_from_world[:3, 3]
            uv = in_view @ k.T
            found.append(uv[:, :2] / uv[:, 2:])
        pixels[side] = np.concatenate(found)
    rows_apart = np.abs(pixels["left"][:, 1] - pixels["right"][:, 1])
    assert float(np.median(rows_apart)) < 0.1 and float(rows_apart.max()) < 0.3, \
        (np.median(rows_apart), rows_apart.max())
    # the disparity is the pair's: u_left - u_right = fx B / z, positive
    assert float(np.min(pixels["left"][:, 0] - pixels["right"][:, 0])) > 0
