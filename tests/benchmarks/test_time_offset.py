"""The time-offset benchmark's pieces without its recordings: the natural case's scaled rig
motion and its row speed, the tables it writes, and a run resumed from its kept results."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.time_offset import (
    OFFSETS_MS,
    Case,
    _results,
    _spec,
    case_of,
    offset_table,
    opencv_rig,
    restamped,
    rig_table,
    row_speed_px_s,
)
from camlog.cli import main
from recorder.scenario import load_scenario
from replay import Image, open_reader
from replay.records import Scenario
from replay.topics import SCENARIO


def test_the_natural_case_scales_the_rig_motion(tmp_path: Path) -> None:
    slow, fast = Case("natural", 0, 17.0), Case("natural", 3, 17.0)
    assert (slow.scale, fast.scale) == (0.25, 1.5)
    base = load_scenario("stereo_moving_rig").rig_motion
    assert base is not None
    for case in (slow, fast):
        motion = load_scenario(str(_spec(case, tmp_path))).rig_motion
        assert motion is not None
        assert motion.rotation_rad == pytest.approx(base.rotation_rad * case.scale)
        assert motion.translation_m == pytest.approx(base.translation_m * case.scale)
    # the same path, scaled: its row speed scales with it (to first order)
    speeds = [row_speed_px_s(Case("natural", seed, 0.0)) for seed in (4, 5, 7)]
    assert speeds[0] > 0 and speeds[2] / speeds[0] == pytest.approx(1.5 / 0.25, rel=0.05)
    assert Case("board", 0, 3.0).key == "board-s0-o+3-x1"
    for case in (Case("natural", 1004, -10.0), Case("board", 3, 17.0), fast):
        assert case_of(case.key) == case


def test_the_tables_say_what_was_measured() -> None:
    results = [{"key": f"board-s{s}-o+17-x1", "error_ms": e, "std_ms": 0.01, "frames": 300}
               for s, e in enumerate([0.01, -0.02, 0.005])]
    results.append({"key": "board-s9-o+17-x1", "why_not": "error: not observable"})
    lines = offset_table("board", results)
    (row,) = [line for line in lines if line.startswith("| +17 |")]
    assert row == "| +17 | 3 of 4 | 0.010 | 0.019 | 1.32 | 300 |"
    assert sum(line.startswith("| ") for line in lines) == 2 + len(OFFSETS_MS)
    rig = rig_table([{"key": "rig-s1",
                      "true": {"baseline_error_percent": 0.01, "rotation_error_deg": 0.004,
                               "joint_views": 300},
                      "estimated": {"baseline_error_percent": 0.012,
                                    "rotation_error_deg": 0.005, "joint_views": 290},
                      "stamps": {"why_not": "camlog calibrate: error: no joint view"},
                      "opencv_stamps": {"baseline_error_percent": 60.0,
                                        "rotation_error_deg": 3.5, "joint_views": 40}}])
    assert any(line == "| camlog, true stamps | 1 of 1 | 0.010 | 0.0040 | 300 |" for line in rig)
    assert any(line.endswith("| 0 of 1: no joint view | | | |") for line in rig)
    assert any(line.endswith("paired by stamps | 1 of 1 | 60.000 | 3.5000 | 40 |") for line in rig)
    assert any(line.endswith("OpenCV stereoCalibrate, true stamps | 0 of 1 | | | |")
               for line in rig)


def test_a_run_resumes_from_its_kept_results(tmp_path: Path) -> None:
    keep = tmp_path / "kept.jsonl"
    keep.write_text(json.dumps({"key": "a", "value": 1}) + "\n" + '{"key": "b", "val')
    ran: list[str] = []

    def run(key: str) -> dict[str, object]:
        ran.append(key)
        return {"key": key, "value": 2}

    results = list(_results(["a", "b"], run, keep))
    assert ran == ["b"]  # the line cut short runs again
    assert [r["value"] for r in results] == [1, 2]
    assert [r["key"] for r in list(_results(["a", "b"], run, keep))] == ["a", "b"]
    assert ran == ["b"]


def test_a_restamped_copy_is_what_the_recorder_writes_with_a_latency(tmp_path: Path) -> None:

    def record(out: Path, *options: str) -> Path:
        assert main(["record", str(_spec(Case("board", 3, 0.0), tmp_path)), "-o", str(out),
                     "--frames", "6", "--resolution", "80x60", "--no-progress", *options]) == 0
        return out

    copy = tmp_path / "copy.mcap"
    restamped(record(tmp_path / "true.mcap"), copy, camera="right", latency_ms=17.0)
    late = record(tmp_path / "late.mcap", "--latency", "right:17")

    def contents(path: Path) -> list[tuple[str, int, object]]:
        with open_reader(path) as reader:
            out: list[tuple[str, int, object]] = []
            for raw in reader.raw_messages():
                message = reader.decode(raw)
                seen: object
                if raw.topic == SCENARIO:
                    record = Scenario.from_message(message)
                    seen = (record.latencies, [c.dropped_frames for c in record.cameras])
                elif isinstance(message, Image):
                    seen = (message.stamp_ns, message.pixels.tobytes())
                else:
                    seen = repr(message)
                out.append((raw.topic, raw.log_time_ns, seen))
            return out

    assert contents(copy) == contents(late)


@pytest.mark.slow
def test_the_opencv_rig_is_the_truth_with_true_stamps_and_far_off_with_late_ones(
        tmp_path: Path) -> None:
    """The harness's plain OpenCV rig: from true stamps within a tenth of the late pairs'
    error (corners numbered alike in both cameras, refined in a window that fits a square)."""
    true = tmp_path / "true.mcap"
    assert main(["record", str(_spec(Case("board", 1, 0.0), tmp_path)), "-o", str(true),
                 "--seed", "1", "--duration", "2", "--resolution", "320x240",
                 "--no-progress"]) == 0
    late = tmp_path / "late.mcap"
    restamped(true, late, camera="right", latency_ms=17.0)
    good, bad = opencv_rig(true), opencv_rig(late)
    assert good["joint_views"] > 20 and bad["joint_views"] > 20
    assert good["baseline_error_percent"] < 0.5 and good["rotation_error_deg"] < 0.05
    assert bad["baseline_error_percent"] > 10 * good["baseline_error_percent"]
    assert bad["rotation_error_deg"] > 10 * good["rotation_error_deg"]
