"""Camera clocks: rate, phase, jitter and drops, in the schedule and in recorded stamps."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from recorder.cameras import CameraSpec
from recorder.clock import camera_times, schedule
from recorder.scenario import builtin_dir, load_scenario

from .logs import Log, record_log

SMALL = {"width": 160, "height": 120}
START_NS = 1_600_000_000_000_000_000


def camera(**changes: object) -> CameraSpec:
    base = load_scenario("mono_checkerboard").cameras[0]
    return dataclasses.replace(base, **changes)


def test_ideal_clock_ticks_at_the_rate_from_the_phase() -> None:
    cam = camera(rate_hz=25.0, phase_s=0.004)
    times, dropped = camera_times(cam, 50, np.random.default_rng(0))
    np.testing.assert_allclose(times, 0.004 + np.arange(50) / 25.0, rtol=0, atol=1e-12)
    assert dropped.size == 0


def test_jitter_is_bounded_and_keeps_order() -> None:
    rate_hz, jitter_s = 30.0, 0.005
    cam = camera(rate_hz=rate_hz, phase_s=0.1, jitter_s=jitter_s)
    times, _ = camera_times(cam, 20_000, np.random.default_rng(1))
    deviation = times - (0.1 + np.arange(times.size) / rate_hz)
    assert np.abs(deviation).max() <= 0.4 / rate_hz + 1e-12
    assert np.all(np.diff(times) > 0)
    # clipping at 0.4 periods (13 ms) barely touches a 5 ms Gaussian
    assert deviation.std() == pytest.approx(jitter_s, rel=0.05)
    assert abs(deviation.mean()) < 1e-4


def test_drops_are_a_share_of_the_frames() -> None:
    n, p = 20_000, 0.1
    times, dropped = camera_times(camera(drop_probability=p), n, np.random.default_rng(2))
    assert times.size + dropped.size == n
    assert np.all(np.diff(dropped) > 0)
    assert abs(dropped.size / n - p) < 4 * np.sqrt(p * (1 - p) / n)
    kept = np.setdiff1d(np.arange(n), dropped)
    np.testing.assert_allclose(times, kept / 30.0, atol=1e-9)


def test_schedule_orders_shots_by_time_then_camera() -> None:
    stereo = load_scenario("stereo_checkerboard").cameras
    shots, drops = schedule(stereo, (5, 5), [np.random.default_rng(i) for i in range(2)])
    assert [(s.camera_index, s.frame_index) for s in shots] == [
        (c, k) for k in range(5) for c in (0, 1)
    ]
    assert all(d.size == 0 for d in drops.values())
    unsynced = load_scenario("stereo_unsynced").cameras
    shots, _ = schedule(unsynced, (300, 300), [np.random.default_rng(i) for i in range(2)])
    times = [s.t_s for s in shots]
    assert times == sorted(times)


# --- recorded stamps of the unsynchronised rig ----------------------------------------------

@pytest.fixture(scope="module")
def lossy_spec(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_unsynced with a known start stamp and 20 % dropped frames."""
    text = (builtin_dir() / "stereo_unsynced.toml").read_text()
    assert text.count("drop_probability = 0.015") == 2
    text = text.replace("drop_probability = 0.015", "drop_probability = 0.2")
    assert text.startswith("#") and "\nrate_hz = 30.0\n" in text
    text = text.replace("\nrate_hz = 30.0\n", f"\nrate_hz = 30.0\nstart_stamp_ns = {START_NS}\n", 1)
    path = tmp_path_factory.mktemp("spec") / "lossy.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def lossy(recording: Callable[..., Log], lossy_spec: Path) -> Log:
    return recording(lossy_spec, frames=120, **SMALL)


def frame_indices(stamps: list[int], rate_hz: float, phase_s: float) -> np.ndarray:
    """Frame index of each stamp: the nearest tick of the camera's ideal clock."""
    t = (np.array(stamps) - START_NS) / 1e9 - phase_s
    index = np.rint(t * rate_hz)
    # jitter is clipped to 0.4 periods, so the nearest tick is unambiguous
    assert np.abs(t * rate_hz - index).max() <= 0.4 + 1e-6
    return index.astype(int)


@pytest.mark.parametrize("name", ["left", "right"])
def test_dropped_frames_in_the_scenario_are_the_missing_ones(lossy: Log, name: str) -> None:
    spec = lossy.scenario["spec"]
    (table,) = (c for c in spec["cameras"] if c["name"] == name)
    namespace = table["namespace"]
    stamps = [image.stamp_ns for image in lossy.images(namespace)]
    indices = frame_indices(stamps, spec["rate_hz"], table.get("phase_s", 0.0))
    assert np.all(np.diff(indices) > 0)
    missing = sorted(set(range(120)) - set(indices.tolist()))
    assert missing, "20 % drops over 120 frames should drop some"
    assert lossy.camera(name)["dropped_frames"] == missing
    assert lossy.result.dropped[name] == missing
    assert lossy.result.frames[name] == len(stamps) == 120 - len(missing)
    assert [m.stamp_ns for m in lossy.infos(namespace)] == stamps
    assert [m.stamp_ns for m in lossy.truths(namespace, "checkerboard")] == stamps


def test_unsynced_stamps_differ_by_the_phase(lossy: Log) -> None:
    spec = lossy.scenario["spec"]
    left_table, right_table = spec["cameras"]
    phase_s = right_table["phase_s"] - left_table.get("phase_s", 0.0)
    assert phase_s > 0
    left = {k: s for s, k in zip(*_stamps_and_indices(lossy, left_table), strict=True)}
    right = {k: s for s, k in zip(*_stamps_and_indices(lossy, right_table), strict=True)}
    assert not set(left.values()) & set(right.values())
    offsets = np.array([right[k] - left[k] for k in sorted(left.keys() & right.keys())]) / 1e9
    assert offsets.size > 50
    # each camera jitters by jitter_s: the offset scatters by sqrt(2) jitter_s around phase
    jitter_s = left_table["jitter_s"]
    assert np.median(offsets) == pytest.approx(phase_s, abs=jitter_s)
    assert offsets.std() == pytest.approx(np.sqrt(2) * jitter_s, rel=0.3)


def _stamps_and_indices(log: Log, table: dict[str, object]) -> tuple[list[int], np.ndarray]:
    stamps = [image.stamp_ns for image in log.images(str(table["namespace"]))]
    phase = table.get("phase_s", 0.0)
    assert isinstance(phase, float)
    return stamps, frame_indices(stamps, log.scenario["spec"]["rate_hz"], phase)


@pytest.mark.slow
def test_same_seed_same_recording(
    recording: Callable[..., Log], lossy_spec: Path, tmp_path: Path
) -> None:
    a = recording(lossy_spec, frames=30, seed=3, **SMALL)
    b = record_log(lossy_spec, tmp_path / "again.mcap", frames=30, seed=3, **SMALL)
    c = recording(lossy_spec, frames=30, seed=4, **SMALL)
    for namespace in ("/unsynced/left", "/unsynced/right"):
        assert a.images(namespace) == b.images(namespace)  # stamps and pixels
        a_stamps = [i.stamp_ns for i in a.images(namespace)]
        c_stamps = [i.stamp_ns for i in c.images(namespace)]
        assert a_stamps != c_stamps
        assert not np.array_equal(a.images(namespace)[0].pixels, c.images(namespace)[0].pixels)
