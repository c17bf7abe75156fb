"""When a pair's windows make a drift: a lasting step, not one window far off on its own."""

from __future__ import annotations

import math

import numpy as np
import pytest

from camlog.check.series import NOISE_SIGMAS, drift_sigmas, noise_scale

STD_DEG, FLOOR_DEG = 0.01, 1e-3


def _metrics(roll_deg: list[float]) -> dict[str, list[float]]:
    """Windows of a pair with the given roll, no pitch, every error ``STD_DEG``."""
    count = len(roll_deg)
    return {"pitch_deg": [0.0] * count, "roll_deg": roll_deg,
            "pitch_std_deg": [STD_DEG] * count, "roll_std_deg": [STD_DEG] * count,
            "rotation_deg": [abs(r) for r in roll_deg]}


def _noise(count: int, seed: int = 0) -> list[float]:
    return list(np.random.default_rng(seed).normal(0.0, STD_DEG, count))


def test_a_lasting_step_is_a_drift_from_its_window() -> None:
    roll = _noise(10)
    roll[4:] = [r + 0.05 for r in roll[4:]]
    sigmas, onset = drift_sigmas(_metrics(roll), 0.0, FLOOR_DEG)
    assert onset == 4
    assert sigmas[4] > NOISE_SIGMAS
    assert max(sigmas[:3]) < sigmas[4]


def test_one_window_far_off_is_not_a_drift() -> None:
    roll = _noise(10)
    roll[6] = 1.0
    _, onset = drift_sigmas(_metrics(roll), 0.0, FLOOR_DEG)
    assert onset is None


def test_the_last_window_alone_is_not_a_drift() -> None:
    roll = _noise(10)
    roll[9] += 0.5
    sigmas, onset = drift_sigmas(_metrics(roll), 0.0, FLOOR_DEG)
    assert onset is None
    assert sigmas[9] == 0.0


def test_a_log_drifted_from_its_start_is_flagged_throughout() -> None:
    roll = [r + 0.05 for r in _noise(8)]
    _, onset = drift_sigmas(_metrics(roll), 0.0, FLOOR_DEG)
    assert onset == 0


def test_the_calibrations_uncertainty_bounds_how_small_a_drift_counts() -> None:
    roll = [r + 0.05 for r in _noise(8)]
    assert drift_sigmas(_metrics(roll), 0.02, FLOOR_DEG)[1] is None


def test_windows_without_a_value_are_left_out() -> None:
    roll = _noise(8)
    roll[5:] = [r + 0.05 for r in roll[5:]]
    roll[2] = math.nan
    sigmas, onset = drift_sigmas(_metrics(roll), 0.0, FLOOR_DEG)
    assert onset == 5
    assert math.isnan(sigmas[2])


def test_the_noise_scale_is_how_much_windows_vary_beyond_their_errors() -> None:
    values = np.random.default_rng(1).normal(0.0, 3 * STD_DEG, 400)
    assert noise_scale(values, np.full(400, STD_DEG)) == pytest.approx(3.0, rel=0.15)
    assert noise_scale(values, np.full(400, 10 * STD_DEG)) == 1.0
