"""Lying stamps: a camera's messages stamped a fixed time after (or before) the exposure they
carry, exposures, jitter and drops unchanged, the truth in the scenario record."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from recorder.clock import schedule
from recorder.errors import ScenarioError
from recorder.latency import LatencySpec, latency_at
from recorder.record import CLOCK_STREAM, rng_for
from recorder.scenario import load_scenario

from .logs import Log

LEFT, RIGHT = "/unsynced/left", "/unsynced/right"
LATE = {"camera": "right", "latency_ms": 17.0}
#: stereo_unsynced: phase, jitter and drops; 60 frames at 80x60 (the stamps are the test)
SMALL = {"frames": 60, "width": 80, "height": 60, "supersample": 1}


@pytest.fixture(scope="module")
def logs(recording: Callable[..., Log]) -> tuple[Log, Log]:
    """The same recording with true stamps and with the right camera stamping 17 ms late
    (the left one 4 ms early)."""
    return (recording("stereo_unsynced", **SMALL),
            recording("stereo_unsynced", **SMALL,
                      latencies=[LATE, {"camera": "/unsynced/left", "latency_ms": -4.0}]))


def _stamps(log: Log, namespace: str) -> np.ndarray:
    return np.array([m.stamp_ns for m in log.images(namespace)], dtype=np.int64)


def test_stamps_move_by_the_latency_and_nothing_else(logs: tuple[Log, Log]) -> None:
    true, late = logs
    np.testing.assert_array_equal(_stamps(late, RIGHT) - _stamps(true, RIGHT), 17_000_000)
    np.testing.assert_array_equal(_stamps(late, LEFT) - _stamps(true, LEFT), -4_000_000)
    for namespace in (LEFT, RIGHT):
        for a, b in zip(true.images(namespace), late.images(namespace), strict=True):
            np.testing.assert_array_equal(a.pixels, b.pixels)
        stamps = _stamps(late, namespace)
        assert [m.stamp_ns for m in late.infos(namespace)] == stamps.tolist()
        assert [m.stamp_ns for m in late.truths(namespace, "checkerboard")] == stamps.tolist()
        for pose, late_pose in zip(true.truths(namespace, "checkerboard"),
                                   late.truths(namespace, "checkerboard"), strict=True):
            np.testing.assert_array_equal(pose.position_m, late_pose.position_m)
    assert true.camera("right")["dropped_frames"] == late.camera("right")["dropped_frames"]
    assert true.camera("right")["dropped_frames"]  # the scenario drops frames


def test_the_scenario_record_says_who_stamps_late(logs: tuple[Log, Log]) -> None:
    true, late = logs
    assert "latencies" not in true.scenario
    assert late.scenario["latencies"] == [
        {"camera": "right", "namespace": RIGHT, "latency_ms": 17.0, "start_s": 0.0},
        {"camera": "left", "namespace": LEFT, "latency_ms": -4.0, "start_s": 0.0}]


def test_messages_are_written_in_stamp_order(logs: tuple[Log, Log]) -> None:
    """Log time is the stamp: a camera stamping late writes after the other's next frame."""
    from replay import open_reader

    with open_reader(logs[1].path) as reader:
        times = [raw.log_time_ns for raw in reader.raw_messages()]
    assert times == sorted(times)
    first_left = int(_stamps(logs[1], LEFT)[0])
    assert times[0] <= first_left  # the scenario record comes first


def test_a_latency_may_start_later() -> None:
    """A driver restarted: the camera's frames exposed from start_s on are stamped anew."""
    scenario = load_scenario("stereo_checkerboard", {"frames": 30, "latencies": [
        {"camera": "right", "latency_ms": 25.0, "start_s": 0.5}]})
    camera = scenario.cameras[1]
    assert latency_at(camera, scenario.latencies, 0.49) == 0.0
    assert latency_at(camera, scenario.latencies, 0.5) == pytest.approx(0.025)
    shots, _ = schedule(scenario.cameras, scenario.frame_counts,
                        [rng_for(scenario, CLOCK_STREAM, i) for i in range(2)],
                        scenario.latencies)
    right = [s for s in shots if s.camera_index == 1]
    assert all(s.stamp_s == s.t_s + (0.025 if s.t_s >= 0.5 else 0.0) for s in right)
    assert [s.stamp_s for s in shots] == sorted(s.stamp_s for s in shots)


@pytest.mark.parametrize(("latencies", "match"), [
    ([{"camera": "middle", "latency_ms": 5.0}], "no camera 'middle'"),
    ([{"camera": "right", "latency_ms": 5000.0}], r"within \[-1000.0, 1000.0\]"),
    ([{"camera": "right", "latency_ms": 5.0, "delay": 1}], "delay: unknown key"),
    ([{"camera": "right"}], "latency_ms: missing"),
    ([LATE, {"camera": "/unsynced/right", "latency_ms": 3.0}], "given two latencies"),
])
def test_bad_latencies_are_one_error(latencies: list[dict[str, object]], match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        load_scenario("stereo_unsynced", {"latencies": latencies})


def test_the_spec_and_the_command_line_say_the_same(tmp_path: Path) -> None:
    spec = tmp_path / "late.toml"
    text = (Path(__file__).resolve().parents[2] / "datasets" / "scenarios"
            / "stereo_unsynced.toml").read_text()
    spec.write_text(text + '\n[[latencies]]\ncamera = "right"\nlatency_ms = 17.0\n')
    assert load_scenario(str(spec)).latencies == (LatencySpec("right", 17.0),)
    printed = StringIO()
    with redirect_stdout(printed):
        assert main(["record", "stereo_unsynced", "-o", str(tmp_path / "late.mcap"),
                     "--frames", "2", "--resolution", "32x24", "--no-progress",
                     "--latency", "right:17", "--latency", "left:-2.5@0.02"]) == 0
    assert "latency: right stamped +17 ms from its exposures" in printed.getvalue()
    assert "latency: left stamped -2.5 ms from its exposures from 0.02 s" in printed.getvalue()


@pytest.mark.parametrize("value", ["right", "right:x", ":17", "right:17@soon"])
def test_a_bad_latency_flag_is_a_usage_error(value: str, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["record", "stereo_unsynced", "-o", str(tmp_path / "x.mcap"), "--latency", value])
    assert exit_info.value.code == 2
    assert "CAMERA:MS" in capsys.readouterr().err
