"""The ideal-corner benchmark's figures: each target reads the figure it names."""

from __future__ import annotations

from benchmarks.calibration_truth import Accuracy
from benchmarks.oracle_views import TARGETS, figures


def test_mono_figures_are_the_worst_of_each_kind() -> None:
    got = figures(Accuracy(-0.03, 0.1, -0.25, [0.12]))
    assert got == {"fx, fy 0.02 %": 0.03, "principal point 0.2 px": 0.25,
                   "max difference 0.2 px": 0.12, "max difference 0.07 px": 0.12}
    assert set(got) <= set(TARGETS)


def test_stereo_figures_add_the_rig() -> None:
    got = figures(Accuracy(0.01, 0.3, 0.1, [0.05, 0.19], rotation_deg=-0.03,
                           baseline_percent=0.015))
    assert got["max difference 0.2 px"] == 0.19
    assert got["rotation 0.02°"] == 0.03
    assert got["baseline 0.02 %"] == 0.015
    assert set(got) == set(TARGETS)
