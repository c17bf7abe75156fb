"""``camlog check`` of a moving rig whose right driver restarts and stamps 25 ms late from then
on: the offset, fitted beside the rotation window by window, is flagged from the restart,
and the rotation, no longer taking the offset for a turn, stays clean."""

from __future__ import annotations

import csv
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np
import pytest

from camlog.check.flow import EXIT_DRIFTED
from camlog.cli import main

pytestmark = pytest.mark.slow

RIGHT = "/stereo_camera/right"
DURATION_S, RESTART_S, LATENCY_MS = 6.0, 3.0, 25.0


@pytest.fixture(scope="module")
def checked(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str], Path]:
    """stereo_moving_rig, 6 s at 320x240, checked in 1 s windows: the report folder, what
    was printed and the log."""
    folder = tmp_path_factory.mktemp("restart")
    log = folder / "restart.mcap"
    assert main(["record", "stereo_moving_rig", "-o", str(log), "--duration", f"{DURATION_S:g}",
                 "--resolution", "320x240", "--latency", f"right:{LATENCY_MS:g}@{RESTART_S:g}",
                 "--no-progress"]) == 0
    printed = StringIO()
    with redirect_stdout(printed):
        assert main(["check", str(log), "--window", "1", "-o", str(folder / "check")]) \
            == EXIT_DRIFTED
    return folder / "check", printed.getvalue().splitlines(), log


def _rows(folder: Path, metric: str) -> list[dict[str, str]]:
    with (folder / "check.csv").open() as f:
        return [r for r in csv.DictReader(f) if r["metric"] == metric]


def test_the_offset_is_measured_window_by_window(checked: tuple[Path, list[str], Path]) -> None:
    rows = _rows(checked[0], "offset_ms")
    before = [float(r["value"]) for r in rows if r["value"] and float(r["end_s"]) <= RESTART_S]
    after = [float(r["value"]) for r in rows if r["value"] and float(r["start_s"]) >= RESTART_S]
    assert len(before) >= 2 and len(after) >= 2
    assert np.median(np.abs(before)) < 0.5
    assert abs(np.median(after) - LATENCY_MS) < 1.0


def test_the_change_is_flagged_from_the_restart_and_the_rotation_is_not(
        checked: tuple[Path, list[str], Path]) -> None:
    folder, printed, log = checked
    changes = _rows(folder, "offset_change_sigmas")
    flagged = sorted({float(r["start_s"]) for r in changes if r["flagged"] == "1"})
    assert flagged[0] == RESTART_S and flagged[-1] == DURATION_S - 1
    rotation = _rows(folder, "drift_sigmas")
    assert not any(r["flagged"] == "1" for r in rotation)
    assert printed[0].startswith(f"{log}: drifted: {RIGHT} from {RESTART_S:g} s, time offset "
                                 "between the cameras' stamps changed from ")
    assert "rotated" not in printed[0]
    assert (folder / "report.md").read_text().count("offset_change_sigmas") == 1
