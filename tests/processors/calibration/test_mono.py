"""Mono calibration of synthetic views: the truth within the stated uncertainty, options kept."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration import validation
from processors.calibration.joint import BoardView, JointResult
from processors.calibration.mono import (
    TANGENTIAL_P_VALUE,
    CalibrationOptions,
    calibrate_mono,
    max_projection_difference,
    tangential_mode,
)
from processors.calibration.validation import cross_validate
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import BOARD, D_TRUE, K_TRUE, H, W, random_poses, true_model, views

NOISE_PX = 0.05  # the simulator's measured corner noise
VIEWS = 30
TRUTH = {"fx": K_TRUE[0, 0], "fy": K_TRUE[1, 1], "cx": K_TRUE[0, 2], "cy": K_TRUE[1, 2],
         **dict(zip(["k1", "k2", "p1", "p2", "k3"], D_TRUE, strict=True))}


@pytest.fixture(scope="module")
def poses() -> list[np.ndarray]:
    return random_poses(np.random.default_rng(1), VIEWS, [true_model()])


def solve(corners: list[np.ndarray], options: CalibrationOptions | None = None,
          **kwargs: bool) -> JointResult:
    return calibrate_mono(BOARD.points_in_board(), corners, (W, H),
                          options or CalibrationOptions(), **kwargs)


def test_recovers_the_camera_within_its_uncertainty(poses: list[np.ndarray]) -> None:
    result = solve(views(true_model(), poses, NOISE_PX, seed=2))
    assert result.used_views(0) == list(range(VIEWS)) and not result.rejected
    params = result.parameters(0)
    assert list(params) == ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"]
    for name, value in params.items():
        sigma = result.std[0][name]
        if name == "k3":  # two radial coefficients by default: k3 is held at 0
            assert value == 0.0 and sigma == 0.0
            continue
        assert sigma > 0
        assert abs(value - TRUTH[name]) < 4 * sigma, f"{name} {value} ± {sigma}"
    # RMS of 2-D residuals of isotropic noise: sigma * sqrt(2), less the fitted parameters
    dof = 2 * VIEWS * BOARD.corner_count
    fitted = 8 + 6 * VIEWS
    expected = NOISE_PX * math.sqrt(2 * (dof - fitted) / dof)
    assert result.rms_px == pytest.approx(expected, rel=0.1)
    for i, residual in enumerate(result.residuals_px):
        rms = math.sqrt(float(np.mean(np.sum(residual**2, axis=1))))
        assert rms == pytest.approx(result.view_rms_px(i), rel=1e-3)
        # view i is board pose i, in the one camera
        assert np.array_equal(result.camera_from_board(i), result.reference_from_board[i])


def test_uncertainty_matches_the_spread_over_noise_draws(poses: list[np.ndarray]) -> None:
    """The reported sigma is the scatter a parameter really shows from one noise draw to the next:
    errors divided by sigma have RMS ≈ 1 over repeated draws."""
    names = ["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"]
    z = []
    for seed in range(24):
        result = solve(views(true_model(), poses, NOISE_PX, seed=100 + seed),
                       reject_outliers=False)
        params = result.parameters(0)
        z.append([(params[n] - TRUTH[n]) / result.std[0][n] for n in names])
    rms_z = float(np.sqrt(np.mean(np.square(z))))
    assert 0.7 < rms_z < 1.4, f"RMS of error/sigma {rms_z:.2f}"
    # sigma scales with the noise
    quiet = solve(views(true_model(), poses, NOISE_PX, seed=5))
    loud = solve(views(true_model(), poses, 2 * NOISE_PX, seed=5))
    for name in names:
        assert loud.std[0][name] / quiet.std[0][name] == pytest.approx(2.0, rel=0.05)


def test_fix_principal_point_holds_the_image_centre(poses: list[np.ndarray]) -> None:
    result = solve(views(true_model(), poses, NOISE_PX, seed=3),
                   CalibrationOptions(fix_principal_point=True))
    assert result.models[0].cx == (W - 1) / 2 and result.models[0].cy == (H - 1) / 2
    assert result.std[0]["cx"] == result.std[0]["cy"] == 0.0


def test_fix_aspect_ratio_forces_square_pixels(poses: list[np.ndarray]) -> None:
    square = K_TRUE.copy()
    square[1, 1] = square[0, 0]
    result = solve(views(true_model(k=square), poses, NOISE_PX, seed=3),
                   CalibrationOptions(fix_aspect_ratio=True))
    assert result.models[0].fx == pytest.approx(result.models[0].fy, rel=1e-12)
    assert abs(result.models[0].fy - square[1, 1]) < 4 * result.std[0]["fy"]


def test_zero_tangent_dist_holds_p1_p2_at_zero(poses: list[np.ndarray]) -> None:
    model = true_model(d=np.array([-0.2, 0.05, 0.0, 0.0, 0.0]))
    result = solve(views(model, poses, NOISE_PX, seed=3),
                   CalibrationOptions(tangential="zero"))
    assert result.models[0].d[2] == result.models[0].d[3] == 0.0
    assert result.std[0]["p1"] == result.std[0]["p2"] == 0.0
    assert abs(result.models[0].d[0] + 0.2) < 4 * result.std[0]["k1"]


def test_one_radial_coefficient(poses: list[np.ndarray]) -> None:
    result = solve(views(true_model(), poses, NOISE_PX, seed=3),
                   CalibrationOptions(k_coefficients=1))
    k1, k2, _p1, _p2, k3 = result.models[0].d
    assert k2 == k3 == 0.0 and k1 < 0
    assert result.models[0].distortion_model == "plumb_bob"


def test_four_coefficients_use_the_rational_model(poses: list[np.ndarray]) -> None:
    result = solve(views(true_model(), poses, NOISE_PX, seed=3),
                   CalibrationOptions(k_coefficients=4))
    assert result.models[0].distortion_model == "rational_polynomial"
    assert result.models[0].d.shape == (8,)
    assert list(result.parameters(0))[4:] == ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"]
    assert result.models[0].d[6] == result.models[0].d[7] == 0.0  # k5, k6 not estimated
    assert result.std[0]["k4"] > 0 and result.std[0]["k5"] == result.std[0]["k6"] == 0.0


def test_k_coefficients_out_of_range() -> None:
    with pytest.raises(ProcessorError, match=r"0\.\.6"):
        CalibrationOptions(k_coefficients=7)


def test_a_noisy_view_is_rejected(poses: list[np.ndarray]) -> None:
    corners = views(true_model(), poses, NOISE_PX, seed=4)
    corners[7] = corners[7] + np.random.default_rng(9).normal(0, 2.0, corners[7].shape)
    result = solve(corners)
    assert set(result.rejected) == {7}
    assert "outlier threshold" in result.rejected[7]
    used = result.used_views(0)
    assert 7 not in used and len(used) == VIEWS - 1
    # without the bad view the camera is as good as ever
    assert abs(result.models[0].fx - K_TRUE[0, 0]) < 4 * result.std[0]["fx"]


def test_too_few_views(poses: list[np.ndarray]) -> None:
    with pytest.raises(ProcessorError, match="too few good views"):
        solve(views(true_model(), poses[:4], NOISE_PX, seed=3))


def test_cross_validation_vanishes_without_noise_and_grows_with_it(
    poses: list[np.ndarray]
) -> None:
    options = [CalibrationOptions(tangential="estimate")]  # the same model in every half
    points = BOARD.points_in_board()

    def halves(noise_px: float, count: int = VIEWS) -> float | None:
        corners = views(true_model(), poses[:count], noise_px, seed=6)
        found = cross_validate(points, [BoardView(0, i, np.arange(BOARD.corner_count), c)
                                        for i, c in enumerate(corners)], [(W, H)], options,
                               range_m=1e4)
        return None if found is None else found[0].worst_px

    exact = halves(0.0)
    assert exact is not None and exact < 0.01
    # the same noise draw scaled: to first order the halves' difference scales with it
    quiet, loud = halves(NOISE_PX), halves(2 * NOISE_PX)
    assert quiet is not None and loud is not None
    assert loud / quiet == pytest.approx(2.0, rel=0.1)
    # the halves are every other point of every view: 8 points make halves too small to use
    corners = views(true_model(), poses, NOISE_PX, seed=6)
    few = [BoardView(0, i, np.arange(8), c[:8]) for i, c in enumerate(corners)]
    assert cross_validate(points, few, [(W, H)], options, range_m=1e4) is None


def test_max_projection_difference() -> None:
    model = true_model()
    assert max_projection_difference(model, model) < 1e-9
    # a pinhole camera with focal length f + df images the ray of pixel p at
    # c + (f + df) (p - c) / f: it moves by df * |p - c| / f, most at the farthest image corner
    f, df = 800.0, 2.0
    k = np.array([[f, 0, 320.0], [0, f, 240.0], [0, 0, 1]])
    a = CameraModel(W, H, k)
    b = CameraModel(W, H, k + np.diag([df, df, 0]))
    farthest = math.hypot(320, 240)
    assert max_projection_difference(a, b, step_px=4) == pytest.approx(df * farthest / f,
                                                                       rel=0.02)
    # only where the views put corners: a 50 px disc about the principal point
    angles = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    disc = np.column_stack([320 + 50 * np.cos(angles), 240 + 50 * np.sin(angles)])
    within = max_projection_difference(a, b, step_px=2, within=disc)
    assert within == pytest.approx(df * 50 / f, rel=0.05)


def test_aligned_projection_difference_discounts_only_a_rotation() -> None:
    f = 800.0
    k = np.array([[f, 0, 320.0], [0, f, 240.0], [0, 0, 1]])
    a = CameraModel(W, H, k)
    # a principal point shift moves every pixel by the same 1 px; turning the camera by
    # 1/f rad explains all of it but the perspective term, 1 px * x^2 at most (x <= 0.4)
    shifted = CameraModel(W, H, k + np.array([[0, 0, 1.0], [0, 0, 0], [0, 0, 0]]))
    assert max_projection_difference(a, shifted) == pytest.approx(1.0, abs=1e-6)
    aligned = max_projection_difference(a, shifted, align_rotation=True)
    assert 0.01 < aligned < 0.4 ** 2
    # a focal length change is radial: no rotation explains any of it
    longer = CameraModel(W, H, k + np.diag([2.0, 2.0, 0]))
    assert max_projection_difference(a, longer, step_px=4, align_rotation=True) == \
        pytest.approx(max_projection_difference(a, longer, step_px=4), rel=0.02)


def test_auto_tangential_drops_p1_p2_when_the_lens_has_none(poses: list[np.ndarray]) -> None:
    model = true_model(d=np.array([-0.2, 0.05, 0.0, 0.0, 0.0]))
    corners = views(model, poses, NOISE_PX, seed=3)
    auto = solve(corners)
    free = solve(corners, CalibrationOptions(tangential="estimate"))
    assert auto.tangential_tests[0] is not None and not auto.tangential_tests[0].estimated
    assert auto.tangential_tests[0].p_value >= TANGENTIAL_P_VALUE
    assert auto.options[0].tangential == "zero" and free.tangential_tests[0] is None
    assert auto.models[0].d[2] == auto.models[0].d[3] == 0.0
    # the principal point is better determined without p1, p2 to trade against
    assert auto.std[0]["cx"] < 0.95 * free.std[0]["cx"]
    assert auto.std[0]["cy"] < 0.95 * free.std[0]["cy"]
    assert abs(auto.models[0].cx - K_TRUE[0, 2]) < 3 * auto.std[0]["cx"]


def test_auto_tangential_statistic_follows_chi_square_2(poses: list[np.ndarray]) -> None:
    """Without tangential distortion, the statistic is chi-square with 2 degrees of freedom
    (mean 2) over noise draws; with the lens's p1, p2 it is far above the threshold."""
    model = true_model(d=np.array([-0.2, 0.05, 0.0, 0.0, 0.0]))
    chi2 = []
    for seed in range(20):
        test = solve(views(model, poses, NOISE_PX, seed=200 + seed),
                     reject_outliers=False).tangential_tests[0]
        assert test is not None
        chi2.append(test.chi2)
    assert 1.0 < float(np.mean(chi2)) < 3.5
    tangential = solve(views(true_model(), poses, NOISE_PX, seed=3))
    assert tangential.tangential_tests[0] is not None and tangential.tangential_tests[0].estimated
    assert tangential.options[0].tangential == "estimate"
    assert abs(tangential.models[0].d[2] - D_TRUE[2]) < 4 * tangential.std[0]["p1"]


def test_tangential_mode_flags() -> None:
    assert tangential_mode(False, False) == "auto"
    assert tangential_mode(True, False) == "zero"
    assert tangential_mode(False, True) == "estimate"
    with pytest.raises(ProcessorError, match="contradict"):
        tangential_mode(True, True)
    with pytest.raises(ProcessorError, match="tangential"):
        CalibrationOptions(tangential="sometimes")


def test_projection_difference_of_fisheye_models() -> None:
    k = np.array([[230.0, 0, 320.0], [0, 230.0, 240.0], [0, 0, 1]])
    a = CameraModel(W, H, k, "equidistant", np.array([0.02, -0.01, 0.0, 0.0]))
    assert max_projection_difference(a, a) < 1e-9
    b = CameraModel(W, H, k + np.diag([1.0, 1.0, 0]), "equidistant", a.d)
    # a focal length 1 px longer images each ray theta_d px farther out: most at the image
    # corner 400 px from the centre, theta_d = 400 / 230
    assert max_projection_difference(a, b) == pytest.approx(400 / 230, rel=1e-6)
    shifted = CameraModel(W, H, k + np.array([[0, 0, 0.5], [0, 0, 0], [0, 0, 0]]),
                          "equidistant", a.d)
    assert max_projection_difference(a, shifted) == pytest.approx(0.5, abs=1e-6)
    assert max_projection_difference(a, shifted, align_rotation=True) < 0.5


def test_opencv_solvers_run_on_one_thread_and_give_the_same_result_twice() -> None:
    """OpenCV's parallel sums change their order from run to run; its calibration runs on
    one thread, and OpenCV's own setting comes back afterwards, also when nested."""
    import cv2

    from processors.calibration.seed import one_opencv_thread

    before = cv2.getNumThreads()
    with one_opencv_thread():
        assert cv2.getNumThreads() == 1
        with one_opencv_thread():
            assert cv2.getNumThreads() == 1
        assert cv2.getNumThreads() == 1
    assert cv2.getNumThreads() == before


def test_cross_validation_is_none_when_a_half_does_not_solve(
    poses: list[np.ndarray], monkeypatch: pytest.MonkeyPatch
) -> None:
    points = BOARD.points_in_board()
    corners = views(true_model(), poses, NOISE_PX, seed=6)
    observed = [BoardView(0, i, np.arange(BOARD.corner_count), c)
                for i, c in enumerate(corners)]
    options = [CalibrationOptions()]
    assert cross_validate(points, observed, [(W, H)], options, range_m=1e4) is not None

    def singular(*_args: object, **_kwargs: object) -> None:
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(validation, "calibrate_cameras", singular)
    assert cross_validate(points, observed, [(W, H)], options, range_m=1e4) is None
