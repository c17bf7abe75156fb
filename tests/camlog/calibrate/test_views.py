"""The detection pass over a recorded log: a ChArUco detection guided by a camera model finds
more corners (beside a single marker, near the border) and places them where the truth says;
what the pass keeps of the frames does not hold on to the log's buffers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camlog.calibrate import views as views_module
from camlog.calibrate.solving import guiding_models
from camlog.calibrate.views import detect_views, size_hint
from camlog.processing.cameras import find_camera
from processors.calibration.board import make_board
from processors.calibration.options import CalibrationOptions
from replay import Image, PoseStamped, open_reader, open_writer
from replay.geometry import rotation_from_quat_xyzw
from replay.records import Scenario
from replay.topics import SCENARIO
from tests.slow import renders

from ..conftest import record, spec_variant

NAMESPACE = "/charuco_camera"
BOARD = make_board("8x6", 0.011, "charuco", marker_m=0.008)


@pytest.fixture(scope="module")
@renders
def charuco_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """mono_charuco (strongly distorted rational lens), 60 frames: 20 poses, a third of them
    cut by the image border."""
    tmp = tmp_path_factory.mktemp("charuco")
    spec = spec_variant("mono_charuco", tmp, {"hold_s = 0.25": "hold_s = 0.1"})
    return record(spec, tmp / "charuco.mcap", "--frames", "60")


def true_corners(path: Path) -> tuple[Scenario, dict[int, np.ndarray]]:
    """The scenario and, per frame stamp, where the true camera images every board corner."""
    scenario, poses = None, {}
    with open_reader(path) as reader:
        for raw in reader.raw_messages():
            if raw.topic == SCENARIO:
                scenario = Scenario.from_message(reader.decode(raw))
            elif raw.topic.startswith(f"{NAMESPACE}/ground_truth/"):
                message = reader.decode(raw)
                assert isinstance(message, PoseStamped)
                poses[message.stamp_ns] = message
    assert scenario is not None
    camera = scenario.camera_for(NAMESPACE)
    assert camera is not None
    points = scenario.targets[0].points_in_target()  # the detector's order, target frame
    assert points is not None
    model = camera.model()
    out = {}
    for stamp, pose in poses.items():
        rotation = rotation_from_quat_xyzw(pose.orientation_xyzw)
        out[stamp] = model.project(points @ rotation.T + pose.position_m)
    return scenario, out


def test_guided_charuco_detection_finds_more_corners_where_the_truth_says(
        charuco_log: Path) -> None:
    scenario, truth = true_corners(charuco_log)
    camera = scenario.camera_for(NAMESPACE)
    assert camera is not None
    with open_reader(charuco_log) as reader:
        source = find_camera(reader, NAMESPACE)
        plain = detect_views(reader, [source], BOARD, workers=2, progress=False)
        guided = detect_views(reader, [source], BOARD, workers=2, progress=False,
                              models={NAMESPACE: camera.model()})
    counts, errors = [0, 0], []
    for frame_plain, frame_guided in zip(plain.cameras[0].distinct(),
                                         guided.cameras[0].distinct(), strict=True):
        for n, frame in enumerate((frame_plain, frame_guided)):
            if frame.detection is not None and frame.detection.accepted:
                counts[n] += len(frame.detection.ids)
        d = frame_guided.detection
        if d is not None and d.accepted:
            errors.append(d.corners_px - truth[frame_guided.stamp_ns][d.ids])
    error = np.linalg.norm(np.concatenate(errors), axis=1)
    assert counts[1] > 1.03 * counts[0], counts
    assert np.sqrt(np.mean(error ** 2)) < 0.2 and error.max() < 0.6, (
        np.sqrt(np.mean(error ** 2)), error.max())


def test_a_fisheye_lens_skips_the_guiding_calibration() -> None:
    # no views at all: a first calibration would fail, so this returning shows none was run
    fisheye = CalibrationOptions(model="equidistant")
    assert guiding_models([], BOARD, fisheye, approximate_s=None) == {}


def test_the_frames_kept_for_detection_and_size_hints_are_copies(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # a mono8 frame is a view of its decompressed chunk: a kept view would keep the chunk
    path = tmp_path / "noise.mcap"
    rng = np.random.default_rng(0)
    with open_writer(path) as writer:
        for i in range(40):
            stamp = (i + 1) * 50_000_000
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8",
                                                 rng.integers(0, 256, (48, 64), np.uint8)),
                         log_time_ns=stamp)
    waiting: list[np.ndarray] = []

    def detect_segment(grays: list[np.ndarray], *args: object) -> list[None]:
        waiting.extend(grays)
        return [None] * len(grays)

    monkeypatch.setattr(views_module, "detect_segment", detect_segment)
    with open_reader(path) as reader:
        found = detect_views(reader, [find_camera(reader, "/cam")], make_board(
            "7x6", 0.01, "chessboard"), workers=2, progress=False)
    samples = found.cameras[0].samples
    assert len(samples) > 1 and len(waiting) == 40
    assert all(gray.base is None and gray.shape == (48, 64) for gray in [*samples, *waiting])


@pytest.mark.parametrize("legacy_pattern", [False, True])
def test_a_charuco_board_of_the_other_layout_is_named_in_the_hint(
        tmp_path: Path, legacy_pattern: bool) -> None:
    # 8x6 squares (an even number of rows): the frames show the other layout's board, whose
    # markers are found but whose corners are not
    shown = make_board("8x6", 0.02, "charuco", marker_m=0.015,
                       legacy_pattern=not legacy_pattern)
    asked = make_board("8x6", 0.02, "charuco", marker_m=0.015, legacy_pattern=legacy_pattern)
    gray = shown.charuco().generateImage((640, 480), marginSize=40)
    path = tmp_path / "board.mcap"
    with open_writer(path) as writer:
        for i in range(3):
            stamp = (i + 1) * 1_000_000_000
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", gray),
                         log_time_ns=stamp)
    with open_reader(path) as reader:
        found = detect_views(reader, [find_camera(reader, "/cam")], asked, workers=1,
                             progress=False)
    camera = found.cameras[0]
    assert all(frame.detection is None for frame in camera.frames)
    expected = ("leave out --legacy-pattern" if legacy_pattern
                else "before 4.6 did: add --legacy-pattern")
    assert expected in size_hint(camera, asked)
    assert size_hint(camera, shown) == ""


def test_true_poses_are_kept_only_where_a_view_can_read_them(charuco_log: Path) -> None:
    scenario, truth = true_corners(charuco_log)
    camera, points = scenario.camera_for(NAMESPACE), scenario.targets[0].points_in_target()
    assert camera is not None and points is not None
    with open_reader(charuco_log) as reader:
        found = detect_views(reader, [find_camera(reader, NAMESPACE)], BOARD, workers=2,
                             progress=False)
    views = found.cameras[0]
    (poses,) = views.true_camera_from_target.values()
    with_board = [f for f in views.distinct() if f.detection is not None]
    assert set(poses) == {f.stamp_ns for f in with_board}
    assert len(poses) < len(views.frames) == len(truth)  # held poses repeat frames
    model = camera.model()
    for frame in with_board:
        pose = poses[frame.stamp_ns]
        np.testing.assert_allclose(model.project(points @ pose[:3, :3].T + pose[:3, 3]),
                                   truth[frame.stamp_ns], atol=1e-9)
