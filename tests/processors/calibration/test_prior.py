"""The prior on the distortion coefficients: it decides what the corners leave free, and
nothing they hold."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration import prior
from processors.calibration.board import Board
from processors.calibration.joint import JointResult, calibrate_cameras
from processors.calibration.lens import model_of
from processors.calibration.options import CalibrationOptions
from replay.camera import CameraModel

from .synthetic import H, W
from .test_accuracy import aimed_poses, max_difference_px, observe

#: k1 k2 p1 p2 k3 fitted whole
K3 = CalibrationOptions(k_coefficients=3, tangential="estimate")
BOARD = Board(7, 6, 0.01)


def lens(hfov_rad: float, d: tuple[float, ...]) -> CameraModel:
    focal_px = W / 2 / math.tan(hfov_rad / 2)
    return CameraModel(W, H, np.array([[focal_px, 0, 321.0], [0, focal_px, 238.0], [0, 0, 1]]),
                       "plumb_bob", np.array(d))


#: 34 degrees across (vs_mrcal's moving board through a k3 lens): r < 0.4 at the image corners
NARROW = lens(0.6, (-0.25, 0.1, 0.0, 0.0, -0.018))
#: 69 degrees across with a strong k3
WIDE = lens(1.2, (-0.28, 0.12, 0.0, 0.0, -0.04))


def solve(truth: CameraModel, *, spread: float, distance_m: tuple[float, float]) -> JointResult:
    """Calibration from 80 views of boards ``distance_m`` away aimed at the middle ``spread``
    of the image (whole boards only; with ``spread`` 1 the boards the border cuts too)."""
    poses = aimed_poses(truth, 80, np.random.default_rng(0), board=BOARD,
                        distance_m=distance_m, spread=spread)
    views = observe(truth, poses, BOARD, seed=100, partial=spread == 1.0)
    return calibrate_cameras(BOARD.points_in_board(), views, [(W, H)], K3)


def test_k3_of_a_narrow_lens_held_by_the_prior(monkeypatch: pytest.MonkeyPatch) -> None:
    """Boards over the middle 40 % of a narrow lens's image: r^2, r^4 and r^6 are nearly
    collinear where the corners are, so without the prior k3 wanders by its sigma of more
    than 1, traded against k2, and the image corners are off by more than a pixel; with it
    they are off by a fifth of a pixel."""
    held = solve(NARROW, spread=0.4, distance_m=(0.25, 0.4))
    k3, sigma = held.models[0].d[4], held.std[0]["k3"]
    assert abs(k3 - NARROW.d[4]) < 0.1 and abs(k3 - NARROW.d[4]) < 3 * sigma
    # the prior's pull on what the views leave free: 0.19 px at the image corners
    assert max_difference_px(held.models[0], NARROW) < 0.25
    monkeypatch.setattr(prior, "PRIOR_SHARE", 0.0)
    free = solve(NARROW, spread=0.4, distance_m=(0.25, 0.4))
    assert free.std[0]["k3"] > 1.0
    assert abs(free.models[0].d[4] - NARROW.d[4]) > 1.0
    assert max_difference_px(free.models[0], NARROW) > 1.0


def test_coefficients_the_views_hold_are_not_moved(monkeypatch: pytest.MonkeyPatch) -> None:
    """Boards over the whole image of a wide lens, the border's cut ones included, hold k3
    to 1e-4: the prior moves k1, k2 and k3 by a small fraction of their sigmas."""
    held = solve(WIDE, spread=1.0, distance_m=(0.08, 0.14))
    monkeypatch.setattr(prior, "PRIOR_SHARE", 0.0)
    free = solve(WIDE, spread=1.0, distance_m=(0.08, 0.14))
    for name, index in (("k1", 0), ("k2", 1), ("k3", 4)):
        shift = held.models[0].d[index] - free.models[0].d[index]
        assert abs(shift) < 0.05 * free.std[0][name], name
    assert abs(held.models[0].d[4] - WIDE.d[4]) < 3 * held.std[0]["k3"]
    assert max_difference_px(held.models[0], WIDE) < 0.15


def test_the_weight_grows_with_the_square_root_of_the_corners() -> None:
    """mrcal 2.5's rule: the prior keeps one share of the corners' cost, whatever their count;
    the denominator is held five times as hard."""
    assert prior.coefficient_px("plumb_bob", 4 * 1260) == pytest.approx(
        2 * prior.coefficient_px("plumb_bob", 1260))
    assert prior.coefficient_px("plumb_bob", 1260) == pytest.approx(
        math.sqrt(0.0025 * 2 * 1260 / (5 * 2.0 ** 2)))
    names, columns = [["k1", "k2", "k3", "k4"]], [np.arange(4)]
    got = prior.weights(["rational_polynomial"], names, columns, 4, [2000])
    np.testing.assert_allclose(got[3], prior.DENOMINATOR_FACTOR * got[0])


def test_the_stated_uncertainty_assumes_the_stated_width() -> None:
    """Where the views leave k3 free its sigma is the prior's: the covariance takes the
    prior at its stated width (0.3 px per unit), not at the solve's weight (0.92 px per unit
    for these 80 views), so the stated sigma of k3 is the wider one and the error is within
    it."""
    held = solve(NARROW, spread=0.4, distance_m=(0.25, 0.4))
    problem = held.problem
    radial = [c for c, n in zip(problem.layout.intrinsic_columns[0], problem.layout.names[0],
                                strict=True) if n in prior.RADIAL]
    assert problem.layout.prior_px[radial].min() > 0.9
    np.testing.assert_allclose(problem.layout.stated_prior_px[radial], prior.STATED_RADIAL_PX)
    column = radial[-1]  # k3
    solved_std = problem.sigma_px * math.sqrt(problem.normal.global_covariance()[column, column])
    assert held.std[0]["k3"] > 2 * solved_std
    assert abs(held.models[0].d[4] - NARROW.d[4]) < 3 * held.std[0]["k3"]


def test_the_solution_at_the_stated_width_is_one_step_away(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """``Problem.at_stated_prior``: the lens as it could be (k3 beyond the views is judged
    against it), the prior at 0.3 px per unit where the solve's weight (0.92 here) pulls k3
    further towards zero: one Gauss-Newton step from the solve lands where a whole solve at
    that width does, to within a hundredth of the step."""
    poses = aimed_poses(NARROW, 80, np.random.default_rng(0), board=BOARD,
                        distance_m=(0.25, 0.4), spread=0.4)
    views = observe(NARROW, poses, BOARD, seed=100, partial=False)
    pulled = calibrate_cameras(BOARD.points_in_board(), views, [(W, H)], K3)
    stepped = model_of("plumb_bob", pulled.problem.at_stated_prior().intrinsics[0], (W, H))
    monkeypatch.setattr(prior, "weights", prior.stated_weights)
    whole = calibrate_cameras(BOARD.points_in_board(), views, [(W, H)], K3,
                              seeds=pulled.models).models[0]
    assert abs(whole.d[4]) > abs(pulled.models[0].d[4]) + 0.02  # k3: held less
    step_px = max_difference_px(pulled.models[0], whole)
    assert step_px > 0.05
    assert max_difference_px(stepped, whole) < 0.01 * step_px
