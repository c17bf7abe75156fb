"""The radial order chosen by cross-validation over whole views: k3 where the lens has a
sizeable one, k1 k2 where it has none, also when every view's corners share an error."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from processors.calibration.model_order import (
    EXACT_RANKS,
    MIN_ORDER_VIEWS,
    OrderChoice,
    choose_order,
    choose_orders,
    order_candidates,
    order_label,
    signed_rank_p,
)
from processors.calibration.options import CalibrationOptions
from processors.calibration.robust import BoardView
from processors.errors import ProcessorError
from replay.camera import CameraModel
from replay.messages import F64

from . import synthetic as s

#: a wide lens (fx 500 px on 640x480): the image corners lie at r = 0.8, where k3 shows
K_WIDE = np.array([[500.0, 0.0, 326.0], [0.0, 503.0, 233.0], [0.0, 0.0, 1.0]])
WITH_K3 = np.array([-0.3, 0.1, 0.0, 0.0, -0.1])
WITHOUT_K3 = np.array([-0.3, 0.1, 0.0, 0.0, 0.0])
POINTS = s.BOARD.points_in_board()
IDS = np.arange(len(POINTS))


def aimed_poses(rng: np.random.Generator, count: int, model: CameraModel) -> list[F64]:
    """``count`` board poses aimed at pixels spread over the whole image, corners included
    (every corner inside it by :data:`synthetic.MARGIN_PX`)."""
    extents = np.array([(s.BOARD.cols - 1) * s.BOARD.square_m,
                        (s.BOARD.rows - 1) * s.BOARD.square_m, 0.0])
    board_from_centred = np.eye(4)
    board_from_centred[:3, 3] = -extents / 2
    poses: list[F64] = []
    while len(poses) < count:
        aim_px = np.array([rng.uniform(0, s.W), rng.uniform(0, s.H), 1.0])
        centre = np.linalg.solve(K_WIDE, aim_px) * rng.uniform(0.25, 0.45)
        angle = rng.uniform(0, 2 * np.pi)
        tilt = rng.uniform(0, 0.6) * np.array([np.cos(angle), np.sin(angle), 0.0])
        roll = s.pose(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]), np.zeros(3))
        candidate = s.pose(tilt, centre) @ roll @ board_from_centred
        uv = s.project(model, candidate)
        if (uv >= s.MARGIN_PX).all() and (uv[:, 0] <= s.W - 1 - s.MARGIN_PX).all() \
                and (uv[:, 1] <= s.H - 1 - s.MARGIN_PX).all():
            poses.append(candidate)
    return poses


def board_views(d: F64, seed: int, *, shared_px: float = 0.0, count: int = 30,
                noise_px: float = 0.15) -> list[F64]:
    """Corners of ``count`` views through the wide lens with distortion ``d``, Gaussian noise
    per corner, and with ``shared_px`` an error every corner of a view shares: a shift of
    that size and a stretch of that size across the board (as a board moving during the
    exposure gives)."""
    model = CameraModel(s.W, s.H, K_WIDE, "plumb_bob", d)
    rng = np.random.default_rng(seed)
    corners = s.views(model, aimed_poses(rng, count, model), noise_px, seed)
    if shared_px:
        corners = [c + rng.normal(0.0, shared_px, 2)
                   + (c - c.mean(axis=0)) @ rng.normal(0.0, shared_px / 150.0, (2, 2))
                   for c in corners]
    return corners


def choice_of(corners: list[F64]) -> OrderChoice:
    return choose_order(POINTS, [(IDS, c) for c in corners], (s.W, s.H),
                        order_candidates(CalibrationOptions(choose_order=True)))


def chosen(corners: list[F64]) -> str:
    return order_label(choice_of(corners).options)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_sizeable_k3_is_chosen(seed: int) -> None:
    assert chosen(board_views(WITH_K3, seed)) == "plumb_bob k1 k2 k3"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_without_k3_k1_k2_are_kept(seed: int) -> None:
    choice = choice_of(board_views(WITHOUT_K3, seed))
    assert order_label(choice.options) == "plumb_bob k1 k2"
    assert len(choice.candidates) == 2  # k3 not needed: rational_polynomial is not tried


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_errors_shared_within_views_do_not_ask_for_more(seed: int) -> None:
    # each view's corners share an error 3x their own noise: the case in which a likelihood
    # ratio over corners finds k3 "needed"
    assert chosen(board_views(WITHOUT_K3, seed, shared_px=0.5)) == "plumb_bob k1 k2"


def test_a_sizeable_k3_is_chosen_through_errors_shared_within_views() -> None:
    assert chosen(board_views(WITH_K3, 0, shared_px=0.05, count=40)) == "plumb_bob k1 k2 k3"


def test_the_choice_states_every_candidate_held_out() -> None:
    choice = choice_of(board_views(WITH_K3, 0))
    assert choice.views == 30 and choice.folds == 5
    small, k3, _rational = choice.held_out_rms_px
    assert k3 < small  # the held-out error shows the lens's k3
    # about the corner noise (0.21 px in 2-D, less the pose fitted to the view itself)
    assert 0.18 < k3 < 0.25
    assert [step.bigger for step in choice.steps] == [1, 2]
    assert choice.steps[0].taken and not choice.steps[1].taken
    text = choice.describe()
    assert "plumb_bob k1 k2 k3 chosen" in text and f"{small:.4f}" in text


def test_too_few_views_keep_the_smallest_order() -> None:
    choice = choice_of(board_views(WITH_K3, 0, count=MIN_ORDER_VIEWS - 1))
    assert order_label(choice.options) == "plumb_bob k1 k2" and choice.why_not is not None
    assert choice.held_out_rms_px == [] and choice.views == 0
    assert "not cross-validated" in choice.describe()


def test_every_camera_chooses_from_its_own_views() -> None:
    with_k3, without = board_views(WITH_K3, 0), board_views(WITHOUT_K3, 1)
    views = [BoardView(camera, i, IDS, c) for camera, corners in enumerate((with_k3, without))
             for i, c in enumerate(corners)]
    options = CalibrationOptions(choose_order=True)
    choices = choose_orders(POINTS, views, [(s.W, s.H)] * 2, options)
    assert [order_label(c.options) for c in choices if c is not None] == \
        ["plumb_bob k1 k2 k3", "plumb_bob k1 k2"]
    assert choose_orders(POINTS, views, [(s.W, s.H)] * 2, CalibrationOptions()) == [None, None]


def test_the_cameras_and_folds_on_threads_choose_as_one_after_another() -> None:
    per_camera = [board_views(WITH_K3, 2, count=20), board_views(WITHOUT_K3, 3, count=20)]
    views = [BoardView(camera, i, IDS, c) for camera, corners in enumerate(per_camera)
             for i, c in enumerate(corners)]
    options = CalibrationOptions(choose_order=True)
    threaded = choose_orders(POINTS, views, [(s.W, s.H)] * 2, options)
    for choice, corners in zip(threaded, per_camera, strict=True):
        alone = choose_order(POINTS, [(IDS, c) for c in corners], (s.W, s.H),
                             order_candidates(options), fold_map=map)
        assert choice is not None and choice.steps == alone.steps
        assert choice.chosen == alone.chosen and len(choice.held_out_px2) > 1
        for mine, theirs in zip(choice.held_out_px2, alone.held_out_px2, strict=True):
            np.testing.assert_array_equal(mine, theirs)  # the same fits, bit for bit


def test_the_ladder_follows_the_model_named() -> None:
    labels = [order_label(o) for o in order_candidates(CalibrationOptions(choose_order=True))]
    assert labels == ["plumb_bob k1 k2", "plumb_bob k1 k2 k3", "rational_polynomial k1..k6"]
    named = order_candidates(CalibrationOptions(model="plumb_bob", choose_order=True))
    assert [order_label(o) for o in named] == ["plumb_bob k1 k2", "plumb_bob k1 k2 k3"]
    assert not any(o.choose_order for o in named)


@pytest.mark.parametrize("given", [{"k_coefficients": 3}, {"model": "equidistant"},
                                   {"model": "rational_polynomial"}])
def test_an_order_given_is_not_chosen(given: dict[str, object]) -> None:
    with pytest.raises(ProcessorError, match="radial order is chosen"):
        CalibrationOptions(choose_order=True, **given)  # type: ignore[arg-type]


def test_signed_rank_p_is_the_exact_law() -> None:
    # every one of 12 views gains: 1 sign pattern in 2^12 does as well
    assert signed_rank_p(np.arange(1.0, 13.0)) == pytest.approx(2.0 ** -12)
    assert signed_rank_p(-np.arange(1.0, 13.0)) == 1.0
    # ranks 1..4 with signs + - + -: a positive sum of 4 or more in 11 of 16 patterns
    assert signed_rank_p(np.array([0.1, -0.2, 0.3, -0.4])) == pytest.approx(11 / 16)
    # tied sizes share their mean rank: + + - -, ranks 1.5 1.5 3.5 3.5
    assert signed_rank_p(np.array([1.0, 1.0, -2.0, -2.0])) == pytest.approx(13 / 16)
    # one huge gain among small losses is one rank, not a mean
    assert signed_rank_p(np.array([-0.1] * 19 + [100.0])) > 0.5


def differences(rng: np.random.Generator, count: int, *, ties: bool) -> F64:
    """``count`` paired differences leaning a little positive; with ``ties``, rounded so
    that many sizes repeat (none zero)."""
    d = rng.normal(0.1, 1.0, count)
    return np.round(d, 1) + 0.05 if ties else d


@pytest.mark.parametrize("count", [5, 12, 40, EXACT_RANKS])
def test_signed_rank_p_is_scipys_exact_law_without_ties(count: int) -> None:
    d = differences(np.random.default_rng(count), count, ties=False)
    expected = stats.wilcoxon(d, alternative="greater", method="exact").pvalue
    assert signed_rank_p(d) == pytest.approx(expected, rel=1e-9, abs=1e-15)


@pytest.mark.parametrize("count", [5, 9, 13])
def test_signed_rank_p_with_ties_is_scipys_permutation_law(count: int) -> None:
    """With tied sizes the law is that of the mean ranks' signs: scipy enumerates every sign
    pattern below 2^14 of them."""
    d = differences(np.random.default_rng(100 + count), count, ties=True)
    d[0] = d[1] = abs(d[1]) or 0.3  # at least one tie
    expected = stats.wilcoxon(d, alternative="greater",
                              method=stats.PermutationMethod()).pvalue
    assert signed_rank_p(d) == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("count", [EXACT_RANKS + 1, 1_192, 50_000])
def test_signed_rank_p_of_many_views_is_scipys_normal_approximation(count: int) -> None:
    """Past the exact sums (whose counts of sign patterns once overflowed: p = NaN from 1 200
    views on) the normal law with the ties' share of the variance taken out and a continuity
    correction, finite however many views."""
    rng = np.random.default_rng(count)
    for ties in (False, True):
        d = differences(rng, count, ties=ties)
        with np.errstate(all="raise"):
            p = signed_rank_p(d)
        expected = stats.wilcoxon(d, alternative="greater", method="asymptotic",
                                  correction=True).pvalue
        assert 0.0 <= p <= 1.0
        assert p == pytest.approx(expected, rel=1e-9, abs=1e-300)
    # zeros are left out
    assert signed_rank_p(np.concatenate([d, np.zeros(10)])) == signed_rank_p(d)
    # no lean: p near one half, however many views
    balanced = np.concatenate([np.arange(1.0, count // 2 + 1), -np.arange(1.0, count // 2 + 1)])
    assert signed_rank_p(balanced) == pytest.approx(0.5, abs=0.05)


def test_the_approximation_takes_over_where_it_agrees_with_the_exact_law() -> None:
    rng = np.random.default_rng(7)
    for _ in range(5):
        d = rng.normal(0.15, 1.0, EXACT_RANKS)
        exact = signed_rank_p(d)
        approximate = stats.wilcoxon(d, alternative="greater", method="asymptotic").pvalue
        assert abs(exact - approximate) < 1e-3
