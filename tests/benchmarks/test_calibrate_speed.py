"""The accuracy benchmark's summary of error/sigma: normal draws read as a right sigma, draws
twice as wide do not."""

from __future__ import annotations

import re

import numpy as np

from benchmarks.calibrate_speed import z_line


def _figures(line: str) -> tuple[float, float, float]:
    rms, beyond2, beyond3 = re.search(
        r"RMS ([\d.]+) .* beyond 2σ ([\d.]+) % .* beyond 3σ ([\d.]+) %", line).groups()
    return float(rms), float(beyond2), float(beyond3)


def test_normal_draws_read_as_a_right_sigma() -> None:
    draws = list(np.random.default_rng(0).normal(size=4000))
    rms, beyond2, beyond3 = _figures(z_line("case", draws))
    assert abs(rms - 1.0) < 0.05
    assert 3.5 < beyond2 < 5.7
    assert beyond3 < 0.8


def test_an_understated_sigma_shows() -> None:
    draws = list(2.0 * np.random.default_rng(1).normal(size=4000))
    rms, beyond2, beyond3 = _figures(z_line("case", draws))
    assert rms > 1.8
    assert beyond2 > 25
    assert beyond3 > 10


def test_no_estimates() -> None:
    assert z_line("case", []) == "case: no estimates"
