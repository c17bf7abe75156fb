"""Motion blur: the noise law fitted from the residuals weights blurred views down."""

from __future__ import annotations

import numpy as np
import pytest

from processors.calibration.joint import BoardView, calibrate_cameras
from processors.calibration.lens import intrinsics_of
from processors.calibration.motion import BLUR_NOISE_FACTOR, BlurModel, fit_blur
from processors.calibration.options import CalibrationOptions

from .synthetic import BOARD, H, W, random_poses, true_model, views

STILL_PX, GROWTH = 0.05, 0.02  # noise sqrt(0.05^2 + (0.02 v)^2) at v px/frame
POINTS = BOARD.points_in_board()
ALL = np.arange(BOARD.corner_count)


def test_fit_recovers_the_law() -> None:
    rng = np.random.default_rng(0)
    speed = rng.uniform(0, 10, 400)
    corners = np.full(400, 48.0)
    variance = STILL_PX ** 2 + GROWTH ** 2 * speed ** 2
    # mean of 2n squared Gaussians of that variance
    mean_square = variance * rng.chisquare(96, 400) / 96
    blur = fit_blur(speed, mean_square, corners)
    assert blur is not None
    assert blur.still_var == pytest.approx(STILL_PX ** 2, rel=0.1)
    assert blur.per_speed2 == pytest.approx(GROWTH ** 2, rel=0.1)
    assert float(blur.sigma_px(blur.limit_px)) == pytest.approx(
        BLUR_NOISE_FACTOR * np.sqrt(blur.still_var))
    # no growth, no law
    assert fit_blur(speed, STILL_PX ** 2 * rng.chisquare(96, 400) / 96, corners) is None


def test_weights_fall_with_speed() -> None:
    blur = BlurModel(STILL_PX ** 2, GROWTH ** 2)
    weights = blur.weight(np.array([0.0, 2.5, 10.0]))
    assert weights[0] == 1.0 and weights[0] > weights[1] > weights[2] > 0


def test_blurred_views_are_weighted_down_and_the_worst_left_out() -> None:
    model = true_model()
    poses = random_poses(np.random.default_rng(1), 120, [model])
    exact = views(model, poses, 0.0, seed=0)
    rng = np.random.default_rng(5)
    speed = rng.uniform(0, 12, len(exact))
    sigma = np.sqrt(STILL_PX ** 2 + GROWTH ** 2 * speed ** 2)
    moving = [BoardView(0, i, ALL, c + rng.normal(0, s, c.shape), speed_px=float(v))
              for i, (c, s, v) in enumerate(zip(exact, sigma, speed, strict=True))]
    options = CalibrationOptions(tangential="estimate")
    weighted = calibrate_cameras(POINTS, moving, [(W, H)], options)
    assert weighted.blur is not None
    limit = weighted.blur.limit_px
    assert limit == pytest.approx(np.sqrt(8) * STILL_PX / GROWTH, rel=0.2)
    assert weighted.blurred_views == int((speed > limit).sum()) > 0
    assert all("motion blur" in weighted.rejected[i] for i in np.flatnonzero(speed > limit))
    assert weighted.sigma_px == pytest.approx(STILL_PX, rel=0.1)
    # the same views without their speeds: every corner counts alike
    plain = calibrate_cameras(POINTS, [BoardView(0, v.instant, ALL, v.corners_px)
                                       for v in moving], [(W, H)], options)
    assert plain.blur is None and plain.std[0]["cx"] > 1.2 * weighted.std[0]["cx"]
    truth = intrinsics_of(model)
    for result in (weighted, plain):
        estimate = intrinsics_of(result.models[0])
        for i, name in enumerate(("fx", "fy", "cx", "cy")):
            assert abs(estimate[i] - truth[i]) < 3.5 * result.std[0][name]
