"""camlog demo: the quick start's main job, on a short recording."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from camlog.cli import main
from replay import open_reader


@pytest.mark.slow
def test_demo_runs_every_step_and_says_where_outputs_went(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "demo"
    # an earlier run's outputs, stale: the demo owns its folder and replaces them
    (out / "calibration").mkdir(parents=True)
    for stale in ("stereo_unsynced.mcap", "demo.rrd", "calibration/left.yaml"):
        (out / stale).write_bytes(b"an earlier run")
    assert main(["demo", "-o", str(out), "--duration", "4", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    steps = [line.split()[0] for line in printed.splitlines()[:-1]]
    assert steps == ["record", "resync", "calibrate", "record", "process", "view"]
    assert all(" MB  (" in line for line in printed.splitlines()[:-1])  # sizes
    for name in ("stereo_unsynced.mcap", "red_block.mcap", "stereo_synced.mcap",
                 "red_block_processed.mcap", "demo.rrd", "calibration/left.yaml",
                 "calibration/right.yaml", "calibration/report.md"):
        assert (out / name).exists(), name
        assert str(out / name.split("/")[0]) in printed
    summary = json.loads((out / "calibration" / "calibration.json").read_text())
    # the resynced topics keep the simulator's frame ids, so truth is still found
    assert all("truth" in cam["parameters"]["fx"] for cam in summary["cameras"])
    assert summary["stereo"]["baseline_m"] == pytest.approx(0.02, rel=0.01)
    with open_reader(out / "red_block_processed.mcap") as reader:
        assert reader.topics["/stereo_camera/left/red_centroid"].count > 0
        assert reader.topics["/stereo_camera/left/edges"].count > 0
    assert (out / "demo.rrd").stat().st_size > 100_000
    with open_reader(out / "stereo_unsynced.mcap") as reader:  # replaced, not appended to
        assert reader.message_count > 0
    assert "camera_matrix" in (out / "calibration" / "left.yaml").read_text()


@pytest.mark.slow
def test_demo_rejects_a_bad_duration_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "demo"
    with pytest.raises(SystemExit) as exit_info:
        main(["demo", "-o", str(out), "--duration", "0"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["camlog demo: error: argument --duration: expected a number > 0, got 0 "
                   "(see camlog demo --help)"]
    assert not out.exists()
