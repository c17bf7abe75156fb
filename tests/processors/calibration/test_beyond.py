"""Where no board reached: the outline of the views' corners, the parts of the image beyond it
and the worst uncertainty there."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration import beyond
from processors.calibration.beyond import beyond_boards, parts, reached
from processors.calibration.joint import BoardView, JointResult, calibrate_cameras
from processors.calibration.model_order import OrderChoice
from processors.calibration.options import CalibrationOptions

from . import synthetic

POINTS = synthetic.BOARD.points_in_board()

SIZE = (300, 200)


def box(x0: float, y0: float, width: float, height: float) -> np.ndarray:
    u, v = np.meshgrid(np.linspace(x0, x0 + width, 5), np.linspace(y0, y0 + height, 5))
    return np.column_stack([u.ravel(), v.ravel()])


def test_the_outline_of_each_view_is_reached() -> None:
    mask = reached(SIZE, [box(100, 50, 100, 100), np.array([[5.0, 5.0], [6.0, 6.0]])])
    assert mask.shape == (200, 300)
    assert mask[100, 150] and mask[50, 100] and mask[150, 200]  # inside, on its corners
    assert not mask[10, 10] and not mask[190, 290]  # a view of two points has no outline
    assert mask[48, 150] and not mask[40, 150]  # a few pixels' margin


def test_the_parts_are_named_by_thirds() -> None:
    corners = np.array([[5.0, 5.0], [295.0, 195.0]])
    assert parts(corners, SIZE) == "corners of the image"
    assert parts(np.vstack([corners, [[5.0, 100.0]]]), SIZE) == \
        "corners and left edge of the image"
    edges = np.array([[150.0, 5.0], [150.0, 195.0], [5.0, 100.0], [295.0, 100.0]])
    assert parts(edges, SIZE) == "edges of the image"
    assert parts(np.zeros((0, 2)), SIZE) == ""


def test_the_worst_uncertainty_beyond_the_boards() -> None:
    u, v = np.meshgrid(np.linspace(0, 299, 7), np.linspace(0, 199, 5))
    pixels = np.stack([u, v], axis=2)
    sigma = 0.01 + np.hypot(pixels[..., 0] - 150, pixels[..., 1] - 100) / 1000
    sigma[0, 0] = np.nan  # no figure: neither counted nor shared
    beyond = beyond_boards(pixels, sigma, reached(SIZE, [box(60, 40, 180, 120)]))
    assert beyond is not None
    assert beyond.worst_px == np.nanmax(sigma)
    assert beyond.where == "corners and edges of the image"
    outside = np.isfinite(sigma) & ((pixels[..., 0] < 56) | (pixels[..., 0] > 244)
                                    | (pixels[..., 1] < 36) | (pixels[..., 1] > 164))
    assert beyond.share == outside.sum() / np.isfinite(sigma).sum()
    everywhere = reached(SIZE, [np.array([[0.0, 0.0], [299.0, 0.0], [299.0, 199.0],
                                          [0.0, 199.0]])])
    assert beyond_boards(pixels, sigma, everywhere) is None


def _k1_k2_chosen() -> tuple[list[OrderChoice | None], list[CalibrationOptions], JointResult,
                             list[BoardView]]:
    """A lens with k3 seen by views the cross-validation judged to need k1 k2 only."""
    lens = synthetic.true_model(np.array([-0.25, 0.08, 0.0, 0.0, -0.05]))
    poses = synthetic.random_poses(np.random.default_rng(3), 15, [lens])
    views = [BoardView(0, i, np.arange(len(POINTS)), c)
             for i, c in enumerate(synthetic.views(lens, poses, 0.05, 4))]
    ladder = [CalibrationOptions(k_coefficients=k, tangential="zero") for k in (2, 3)]
    order = OrderChoice(ladder, [np.ones(15), np.ones(15)], [], 0, 5)
    joint = calibrate_cameras(POINTS, views, [(synthetic.W, synthetic.H)], ladder[:1])
    return [order], ladder[:1], joint, views


@pytest.mark.parametrize("ratio", [0.0, math.inf])
def test_k3_is_kept_where_k1_k2_do_not_hold_their_figure(monkeypatch: pytest.MonkeyPatch,
                                                          ratio: float) -> None:
    monkeypatch.setattr(beyond, "BEYOND_RATIO", ratio)
    orders, wanted, joint, views = _k1_k2_chosen()
    after, options, solved = beyond.k3_beyond_the_views(
        POINTS, views, [(synthetic.W, synthetic.H)], wanted=wanted, orders=orders, joint=joint)
    (order,) = after
    assert order is not None and order.beyond_ratio is not None and order.beyond_px is not None
    assert order.beyond_ratio > 0 and order.beyond_px > 0
    if ratio == 0.0:  # kept: the k3 fit is the solution
        assert order.options.radial_count == 3 and options[0].radial_count == 3
        assert solved.models[0].d[4] != 0.0 and "k3 kept" in order.describe()
    else:  # k1 k2 kept, the k3 fit their left-out model
        assert order.options.radial_count == 2 and solved is joint
        (left_out,) = solved.left_out_models
        assert left_out is not None and left_out.d[4] != 0.0
        assert "k1 k2 kept" in order.describe()


def test_nothing_is_set_beside_an_order_not_chosen_by_the_views() -> None:
    _orders, wanted, joint, views = _k1_k2_chosen()
    assert beyond.k3_beyond_the_views(POINTS, views, [(synthetic.W, synthetic.H)],
                                      wanted=wanted, orders=[None], joint=joint) \
        == ([None], wanted, joint)
