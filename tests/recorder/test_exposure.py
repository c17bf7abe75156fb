"""A board that never stops, and motion blur: sub-frame renders averaged over the exposure,
stamped and truthed at mid-exposure."""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from pathlib import Path

import cv2
import numpy as np
import pytest

from recorder import exposure
from recorder import record as record_module
from recorder.errors import ScenarioError
from recorder.exposure import BLUR_STEP_PX, subframe_count, subframe_times
from recorder.motion import SmoothTrajectory, plan_trajectory
from recorder.record import record
from recorder.render import SceneRenderer
from recorder.scenario import load_scenario
from recorder.targets import outline_in_target
from replay.camera import CameraModel
from replay.geometry import invert

from .logs import Log, transform

SMALL = {"width": 320, "height": 240}
FRAMES = 12


def test_smooth_path_passes_its_waypoints_with_continuous_velocity() -> None:
    scenario = load_scenario("mono_moving_blur", SMALL)
    (target,) = scenario.targets
    trajectory = plan_trajectory(target, scenario.cameras, 4.0, np.random.default_rng(1))
    assert isinstance(trajectory, SmoothTrajectory)
    step = trajectory.segment_s
    dt = 1e-4
    speeds = []
    for t in np.arange(0.01, 4.0, 0.01):
        before, at, after = (trajectory.at(t - dt)[:3, 3], trajectory.at(t)[:3, 3],
                             trajectory.at(t + dt)[:3, 3])
        speeds.append(np.linalg.norm(after - before) / (2 * dt))
        # no jumps in position or velocity, waypoints included
        assert np.linalg.norm((after - at) - (at - before)) < 1e-6
    assert min(speeds) > 1e-3  # never held still
    for k in range(1, 4):
        x, y, z = trajectory.parameters[k, :3]
        # the board's middle is at the waypoint's centre when the path reaches it
        middle = trajectory.at(k * step) @ np.array([0.03, 0.025, 0.0, 1.0])
        np.testing.assert_allclose(middle[:3], [x, y, z], atol=1e-9)


def test_subframes_are_centred_on_the_stamp() -> None:
    times = subframe_times(1.0, 0.004, 4)
    np.testing.assert_allclose(times, [0.9985, 0.9995, 1.0005, 1.0015])
    assert times.mean() == pytest.approx(1.0)


def test_subframes_follow_the_image_motion() -> None:
    scenario = load_scenario("mono_moving_blur")
    (camera,) = scenario.cameras
    (target,) = scenario.targets
    trajectory = plan_trajectory(target, scenario.cameras, 6.0, np.random.default_rng(0))
    outline = outline_in_target(target)
    camera_from_world = invert(camera.world_from_camera)
    for t in np.linspace(0.2, 5.8, 15):
        count = subframe_count(camera, [trajectory], [outline], float(t))
        ends = []
        for s in (t - camera.exposure_s / 2, t + camera.exposure_s / 2):
            pose = camera_from_world @ trajectory.at(float(s))
            ends.append(camera.model.project(outline @ pose[:3, :3].T + pose[:3, 3]))
        moved = float(np.linalg.norm(ends[1] - ends[0], axis=1).max())
        assert count == max(1, min(12, math.ceil(moved / BLUR_STEP_PX)))
    still = load_scenario("mono_checkerboard").cameras[0]
    assert subframe_count(still, [trajectory], [outline], 1.0) == 1


def test_exposure_must_fit_in_a_frame() -> None:
    with pytest.raises(ScenarioError, match="exposure_s"):
        load_scenario("mono_moving_blur", {"exposure_s": 0.04})


@pytest.fixture(scope="module")
def blurred(recording: Callable[..., Log]) -> Log:
    return recording("mono_moving_blur", frames=FRAMES, **SMALL)


@pytest.fixture(scope="module")
def sharp(recording: Callable[..., Log]) -> Log:
    return recording("mono_moving_blur", frames=FRAMES, exposure_s=0.0, **SMALL)


def _sharpness(log: Log) -> float:
    """Mean squared Laplacian over the frames."""
    images = log.images("/simple_camera")
    return float(np.mean([cv2.Laplacian(cv2.cvtColor(i.pixels, cv2.COLOR_RGB2GRAY),
                                        cv2.CV_64F).var() for i in images]))


def test_blur_is_in_the_pixels(blurred: Log, sharp: Log) -> None:
    assert blurred.camera("simple_camera")["exposure_s"] == 0.004
    assert "exposure_s" not in sharp.camera("simple_camera")
    # same motion and stamps, the truth at mid-exposure: the same poses
    for a, b in zip(blurred.truths("/simple_camera", "checkerboard"),
                    sharp.truths("/simple_camera", "checkerboard"), strict=True):
        assert a.stamp_ns == b.stamp_ns
        np.testing.assert_allclose(a.position_m, b.position_m)
    assert _sharpness(blurred) < 0.9 * _sharpness(sharp)


def test_blurred_corners_sit_at_the_mid_exposure_truth(blurred: Log) -> None:
    """Over a short exposure the board moves nearly uniformly, so its blurred corners are
    centred on where the mid-exposure truth puts them."""
    (target,) = blurred.scenario["targets"]
    corners = np.array(target["corners_in_target"])
    cols, rows = target["inner_corners"]
    errors = []
    for image, info, pose in zip(blurred.images("/simple_camera"),
                                 blurred.infos("/simple_camera"),
                                 blurred.truths("/simple_camera", "checkerboard"), strict=True):
        gray = cv2.cvtColor(image.pixels, cv2.COLOR_RGB2GRAY)
        found, detected = cv2.findChessboardCorners(gray, (cols, rows))
        if not found:
            continue
        refined = cv2.cornerSubPix(gray, detected, (5, 5), (-1, -1),
                                   (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4))
        camera_from_board = transform(pose)
        truth = CameraModel.from_camera_info(info).project(
            corners @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
        distances = np.linalg.norm(refined.reshape(-1, 1, 2) - truth[None], axis=2)
        errors.append(distances.min(axis=1))
    assert len(errors) >= FRAMES // 2
    all_errors = np.concatenate(errors)
    assert np.median(all_errors) < 0.2, np.median(all_errors)


#: a held pose's scenes: cameras on their own clocks; the right camera turned mid-pose (its
#: render must change though no target moved); a fisheye's views
HELD = {
    "stereo_unsynced": {"width": 160, "height": 120},
    "stereo_checkerboard": {"width": 160, "height": 120, "drifts": [
        {"camera": "right", "axis": "pitch", "degrees": 0.5, "start_s": 0.2}]},
    "mono_fisheye": {},
}


@pytest.mark.slow
@pytest.mark.parametrize("scenario", list(HELD))
def test_a_held_pose_is_rendered_once_and_logged_as_if_rendered_every_frame(
        scenario: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A held board is rendered once per camera and scene, and every message of the log is
    byte for byte what rendering each frame writes; the noise is still drawn per frame."""
    overrides = {"duration_s": 0.7, "seed": 3, "noise_std": 2.0, **HELD[scenario]}
    renders = 0
    render = SceneRenderer.render

    def counted(self: SceneRenderer, camera_index: int) -> np.ndarray:
        nonlocal renders
        renders += 1
        return render(self, camera_index)

    monkeypatch.setattr(SceneRenderer, "render", counted)
    once = record(load_scenario(scenario, overrides), tmp_path / "once.mcap", progress=False)
    rendered_once, renders = renders, 0
    frames = sum(once.frames.values())
    monkeypatch.setattr(record_module, "rendered_shots",
                        partial(exposure.rendered_shots, every_frame=True))
    record(load_scenario(scenario, overrides), tmp_path / "each.mcap", progress=False)
    assert renders == frames
    cameras = len(once.frames)
    scenes = cameras * math.ceil(overrides["duration_s"] / 0.5) \
        + len(overrides.get("drifts", []))  # poses held 0.5 s each, and a turn
    assert rendered_once <= scenes + cameras < frames / 4
    assert _messages(tmp_path / "once.mcap") == _messages(tmp_path / "each.mcap")
    images = [m for m in _messages(tmp_path / "once.mcap") if m[0].endswith("/image_raw")]
    assert len({data for _, _, data in images}) == len(images)  # no two frames alike


def _messages(path: Path) -> list[tuple[str, int, bytes]]:
    """Every message of an MCAP file as written: topic, log time, serialized bytes."""
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(f).iter_messages()]
