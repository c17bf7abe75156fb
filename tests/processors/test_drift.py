"""Drift from vertical disparities: the small-rotation fit and the window noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.drift import PairMatches, fit_rotation, window_noise
from replay.geometry import rotation_about
from replay.messages import F64

F_PX, CX, CY, BASELINE_M = 500.0, 319.5, 239.5, 0.05
K = np.array([[F_PX, 0, CX], [0, F_PX, CY], [0, 0, 1.0]])


def _project(points: F64) -> F64:
    uv = points @ K.T
    return np.asarray(uv[:, :2] / uv[:, 2:])


def _matches(pitch_deg: float, roll_deg: float, yaw_deg: float = 0.0) -> PairMatches:
    """Points of a scene 1 to 5 m away seen by a rectified pair whose right camera turned."""
    rng = np.random.default_rng(3)
    depth = rng.uniform(1.0, 5.0, 400)
    points = np.column_stack([rng.uniform(-0.6, 0.6, 400) * depth,
                              rng.uniform(-0.45, 0.45, 400) * depth, depth])
    turned = (rotation_about(np.array([1.0, 0, 0]), math.radians(pitch_deg))
              @ rotation_about(np.array([0, 1.0, 0]), math.radians(yaw_deg))
              @ rotation_about(np.array([0, 0, 1.0]), math.radians(roll_deg)))
    in_right = (points - [BASELINE_M, 0, 0]) @ turned  # turned.T applied to each point
    return PairMatches(_project(points), _project(in_right))


def _p_right() -> F64:
    return np.column_stack([K, [-F_PX * BASELINE_M, 0, 0]])


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), [(0.1, 0.0), (0.0, 0.2), (-0.3, 0.15)])
def test_the_fit_finds_the_right_cameras_pitch_and_roll(pitch_deg: float, roll_deg: float
                                                         ) -> None:
    fit = fit_rotation(_matches(pitch_deg, roll_deg), p_rect=_p_right(),
                       rect_from_right=np.eye(3))
    assert math.degrees(fit.pitch_rad) == pytest.approx(pitch_deg, abs=0.003)
    assert math.degrees(fit.roll_rad) == pytest.approx(roll_deg, abs=0.003)
    assert fit.angle_deg == pytest.approx(math.hypot(pitch_deg, roll_deg), abs=0.003)
    assert fit.clean_px < 0.02


def test_outliers_do_not_move_the_fit() -> None:
    good = _matches(0.1, 0.0)
    right = good.right_px.copy()
    right[::10, 1] += 6.0  # a tenth of the matches a few rows off
    fit = fit_rotation(PairMatches(good.left_px, right), p_rect=_p_right(),
                       rect_from_right=np.eye(3))
    assert math.degrees(fit.pitch_rad) == pytest.approx(0.1, abs=0.003)
    assert fit.matches == 360


def test_yaw_barely_moves_the_rows() -> None:
    """A yaw of a side-by-side rig moves points along the rows: over a 100° x 80° view, a
    degree of it leaves a vertical error (median) twenty times smaller than a degree of
    pitch does, and less the narrower the view."""
    yawed = np.abs(_matches(0.0, 0.0, yaw_deg=1.0).dy_px)
    pitched = np.abs(_matches(1.0, 0.0).dy_px)
    assert np.median(yawed) < np.median(pitched) / 20


def test_the_rotation_is_turned_back_into_the_cameras_frame() -> None:
    """The fit is about the rectified axes; a camera whose rectification turns it 90° about
    its optical axis has its rectified x along its own y."""
    rect_from_right = rotation_about(np.array([0, 0, 1.0]), math.pi / 2)
    fit = fit_rotation(_matches(0.2, 0.0), p_rect=_p_right(), rect_from_right=rect_from_right)
    assert math.degrees(fit.pitch_rad) == pytest.approx(0.0, abs=1e-6)
    assert math.degrees(fit.angle_deg) > 0


def test_too_few_matches_give_no_rotation() -> None:
    fit = fit_rotation(PairMatches(np.zeros((2, 2)), np.zeros((2, 2))), p_rect=_p_right(),
                       rect_from_right=np.eye(3))
    assert math.isnan(fit.pitch_rad)
    assert fit.matches == 2


def test_window_noise_ignores_one_step() -> None:
    rng = np.random.default_rng(0)
    values = rng.normal(0.0, 0.1, 200)
    stepped = values + np.where(np.arange(200) >= 100, 5.0, 0.0)
    assert window_noise(values) == pytest.approx(0.1, rel=0.25)
    assert window_noise(stepped) == pytest.approx(window_noise(values), rel=0.05)
    assert window_noise(np.array([1.0, math.nan])) == 0.0


def test_mismatches_that_agree_among_themselves_do_not_pull_the_fit() -> None:
    """A repeating pattern matched one period off: many matches, all a few rows off alike."""
    good = _matches(0.1, 0.0)
    right = good.right_px.copy()
    right[::2, 1] += 4.0  # half the matches, one consistent offset
    right[1::4, 1] += 1.0e-3  # the other half, less one in four: exact
    fit = fit_rotation(PairMatches(good.left_px, right), p_rect=_p_right(),
                       rect_from_right=np.eye(3))
    assert math.degrees(fit.pitch_rad) == pytest.approx(0.1, abs=0.003)


def test_standard_errors_match_the_scatter_of_the_fit() -> None:
    good = _matches(0.0, 0.1)
    rng = np.random.default_rng(5)
    pitch, roll, std = [], [], []
    for _ in range(60):
        noisy = good.right_px + np.column_stack([np.zeros(400), rng.normal(0, 0.1, 400)])
        fit = fit_rotation(PairMatches(good.left_px, noisy), p_rect=_p_right(),
                           rect_from_right=np.eye(3))
        pitch.append(fit.pitch_rad)
        roll.append(fit.roll_rad)
        std.append((fit.pitch_std_rad, fit.roll_std_rad))
    assert np.mean(std, axis=0) == pytest.approx([np.std(pitch), np.std(roll)], rel=0.3)


def test_a_sloppy_view_counts_for_less() -> None:
    """Two views of the same rotation, one with ten times the noise of the other: the fit
    is about as good as the sharp view's alone."""
    good = _matches(0.0, 0.1)
    rng = np.random.default_rng(6)
    noise = np.where(np.arange(400) < 200, 0.02, 0.5) * rng.normal(0, 1, 400)
    noisy = good.right_px + np.column_stack([np.zeros(400), noise])
    views = (np.arange(400) >= 200).astype(np.int64)
    weighted = fit_rotation(PairMatches(good.left_px, noisy), p_rect=_p_right(),
                            rect_from_right=np.eye(3), views=views)
    sharp = fit_rotation(PairMatches(good.left_px[:200], noisy[:200]), p_rect=_p_right(),
                         rect_from_right=np.eye(3))
    assert weighted.roll_std_rad < 1.1 * sharp.roll_std_rad
    assert math.degrees(weighted.roll_rad) == pytest.approx(0.1, abs=0.005)
