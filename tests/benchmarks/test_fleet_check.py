"""The fleet benchmark in small: three logs, two of them drifted (pitch and roll), checked by
a batch on the process engine and on a Ray instance the run starts; both find the drifts,
from within two seconds of their onsets, and nothing in the clean log, with identical
``check.csv`` files."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.fleet_check import ONSET_S, judge, plan_fleet, run_fleet


@pytest.mark.slow
def test_a_small_fleet_is_judged_alike_on_both_engines(tmp_path: Path) -> None:
    fleet = plan_fleet(3, drifted=2, seed=1, axes=("pitch", "roll"))
    assert sorted(log.drift.axis for log in fleet if log.drift) == ["pitch", "roll"]
    found, same, _ = run_fleet(fleet, tmp_path / "cache", tmp_path / "work")
    assert same
    rows, failures = judge(fleet, found)
    assert failures == [], "\n".join(rows)
    for log, got in zip(fleet, found, strict=True):
        if log.drift is None:
            assert got.onset_s is None
        else:
            assert got.onset_s is not None
            assert abs(got.onset_s - log.drift.start_s) <= ONSET_S
            assert abs(got.rotation_deg - abs(log.drift.degrees)) < 0.25 * abs(log.drift.degrees)
