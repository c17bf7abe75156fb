"""Joint calibration of synthetic cameras: truth within the stated uncertainty, outliers found."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration.joint import (
    BoardView,
    JointResult,
    calibrate_cameras,
    threshold_sigma,
)
from processors.calibration.lens import INTRINSIC_NAMES, intrinsics_of
from processors.calibration.options import CalibrationOptions
from processors.calibration.rotation import rotation_vectors
from processors.errors import ProcessorError
from replay.camera import CameraModel

from .synthetic import BOARD, H, W, pose, random_poses, true_model, views

NOISE_PX = 0.05
RIGHT_FROM_LEFT = pose(np.array([0.0, 0.021, 0.0]), np.array([-0.1, 0.0, 0.0]))
POINTS = BOARD.points_in_board()
ALL = np.arange(BOARD.corner_count)


def board_views(models: list[CameraModel], count: int, *, noise_px: float = NOISE_PX,
                seed: int = 0, placements: list[np.ndarray] | None = None
                ) -> tuple[list[BoardView], list[np.ndarray]]:
    placements = placements or [np.eye(4), RIGHT_FROM_LEFT][:len(models)]
    poses = random_poses(np.random.default_rng(seed), count, models,
                         camera_from_reference=placements)
    out = []
    for camera, (model, placement) in enumerate(zip(models, placements, strict=True)):
        corners = views(model, [placement @ p for p in poses], noise_px, seed + 10 * camera + 1)
        out += [BoardView(camera, i, ALL, c) for i, c in enumerate(corners)]
    return out, poses


def errors_in_sigma(result: JointResult, camera: int, truth: CameraModel) -> dict[str, float]:
    names = INTRINSIC_NAMES[truth.distortion_model]
    estimate = intrinsics_of(result.models[camera])
    return {n: (e - t) / result.std[camera][n]
            for n, e, t in zip(names, estimate, intrinsics_of(truth), strict=True)
            if result.std[camera][n] > 0}


def test_mono_recovers_the_camera_within_its_uncertainty() -> None:
    observed, poses = board_views([true_model()], 30)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())
    assert result.tangential_tests[0] is not None and result.tangential_tests[0].estimated
    z = errors_in_sigma(result, 0, true_model())
    assert set(z) == {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}
    assert max(abs(v) for v in z.values()) < 3.5, z
    assert result.sigma_px == pytest.approx(NOISE_PX, rel=0.1)
    assert not result.rejected and result.outlier_corners <= 1
    for instant, truth in enumerate(poses):
        np.testing.assert_allclose(result.reference_from_board[instant][:3, 3], truth[:3, 3],
                                   atol=1e-3)


@pytest.mark.slow
def test_uncertainty_matches_the_spread_over_noise_draws() -> None:
    """error / sigma has RMS about 1 over repeated noise draws: the covariance is honest."""
    z = []
    exact, _ = board_views([true_model()], 15, noise_px=0.0)
    for seed in range(12):
        rng = np.random.default_rng(100 + seed)
        noisy = [BoardView(v.camera, v.instant, v.point_ids,
                           v.corners_px + rng.normal(0, NOISE_PX, (len(ALL), 2))) for v in exact]
        result = calibrate_cameras(POINTS, noisy, [(W, H)],
                                   CalibrationOptions(tangential="estimate"))
        z.append(list(errors_in_sigma(result, 0, true_model()).values()))
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.7 < rms < 1.35, rms


def test_outlier_corners_are_left_out_one_by_one() -> None:
    observed, _ = board_views([true_model()], 30, seed=2)
    planted = set()
    for i in range(0, 30, 3):
        observed[i].corners_px[7] += [1.0, -0.8]  # 25 sigma
        planted.add(i)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())
    found = {i for i, inliers in enumerate(result.inliers) if not inliers[7]}
    assert planted <= found
    assert result.outlier_corners <= len(planted) + 1
    assert not result.rejected  # one bad corner does not cost the view
    assert result.sigma_px == pytest.approx(NOISE_PX, rel=0.1)
    assert max(abs(v) for v in errors_in_sigma(result, 0, true_model()).values()) < 3.5


def test_a_view_that_is_not_the_board_is_dropped() -> None:
    observed, _ = board_views([true_model()], 20, seed=3)
    scrambled = np.random.default_rng(0).permutation(observed[4].corners_px)
    observed[4] = BoardView(0, 4, ALL, scrambled)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())
    assert list(result.rejected) == [4] and "outlier threshold" in result.rejected[4]
    assert max(abs(v) for v in errors_in_sigma(result, 0, true_model()).values()) < 3.5


def test_stereo_refines_both_cameras_and_the_rig() -> None:
    left = true_model()
    right = CameraModel(W, H, np.array([[805.0, 0, 318], [0, 809, 244], [0, 0, 1]]), "plumb_bob",
                        np.array([-0.18, 0.04, 0.0, 0.0, 0.0]))
    observed, _ = board_views([left, right], 30, seed=4)
    result = calibrate_cameras(POINTS, observed, [(W, H)] * 2, CalibrationOptions())
    for camera, truth in enumerate((left, right)):
        z = errors_in_sigma(result, camera, truth)
        assert max(abs(v) for v in z.values()) < 3.5, (camera, z)
    # the joint views make the right camera as good as the left
    for name in ("fx", "cx", "k1"):
        assert result.std[1][name] == pytest.approx(result.std[0][name], rel=0.3)
    rig = result.camera_from_reference[1]
    error = np.concatenate([rotation_vectors((rig[:3, :3] @ RIGHT_FROM_LEFT[:3, :3].T)[None])[0],
                            rig[:3, 3] - RIGHT_FROM_LEFT[:3, 3]])
    covariance = result.rig_covariance[1]
    assert float(error[:3] @ np.linalg.solve(covariance[:3, :3], error[:3])) < 3.5 ** 2
    assert float(error[3:] @ np.linalg.solve(covariance[3:, 3:], error[3:])) < 3.5 ** 2
    assert math.degrees(float(np.linalg.norm(error[:3]))) < 0.1


def test_views_of_one_camera_alone_still_count() -> None:
    """Instants only the right camera saw carry its intrinsics; the rig comes from the rest."""
    observed, _ = board_views([true_model(), true_model()], 24, seed=5)
    only_right = [v for v in observed if not (v.camera == 0 and v.instant >= 16)]
    result = calibrate_cameras(POINTS, only_right, [(W, H)] * 2, CalibrationOptions())
    assert len(result.reference_from_board) == 24
    assert max(abs(v) for v in errors_in_sigma(result, 1, true_model()).values()) < 3.5


@pytest.mark.slow
def test_a_camera_placed_through_another() -> None:
    """Camera 2 never shares an instant with camera 0: it is placed through camera 1."""
    placements = [np.eye(4), RIGHT_FROM_LEFT, RIGHT_FROM_LEFT @ RIGHT_FROM_LEFT]
    models = [true_model()] * 3
    observed, _ = board_views(models, 30, seed=7, placements=placements)
    chain = [v for v in observed if not (v.camera == 0 and v.instant >= 15)
             and not (v.camera == 2 and v.instant < 15)]
    result = calibrate_cameras(POINTS, chain, [(W, H)] * 3, CalibrationOptions())
    for camera in (1, 2):
        rig = result.camera_from_reference[camera]
        truth = placements[camera]
        error = np.concatenate([
            rotation_vectors((rig[:3, :3] @ truth[:3, :3].T)[None])[0], rig[:3, 3] - truth[:3, 3]])
        covariance = result.rig_covariance[camera]
        assert float(error @ np.linalg.solve(covariance, error)) < 4.5 ** 2, camera
    with pytest.raises(ProcessorError, match="directly or through another camera"):
        calibrate_cameras(POINTS, [v for v in chain if v.camera != 1 or v.instant < 15],
                          [(W, H)] * 3, CalibrationOptions())


def test_fisheye_lens() -> None:
    fisheye = CameraModel(W, H, np.array([[230.0, 0, 322], [0, 231, 237], [0, 0, 1]]),
                          "equidistant", np.array([0.02, -0.008, 0.003, -0.0007]))
    observed, _ = board_views([fisheye], 30, seed=6)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions(model="fisheye"))
    assert result.models[0].distortion_model == "equidistant"
    assert result.tangential_tests == [None]
    z = errors_in_sigma(result, 0, fisheye)
    assert set(z) == {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"}
    assert max(abs(v) for v in z.values()) < 3.5, z


def test_options_hold_what_they_say() -> None:
    observed, _ = board_views([true_model()], 20, seed=7)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions(
        fix_principal_point=True, fix_aspect_ratio=True, tangential="zero", k_coefficients=1))
    model = result.models[0]
    assert model.fx == pytest.approx(model.fy, rel=1e-9)
    assert (model.cx, model.cy) == ((W - 1) / 2, (H - 1) / 2)
    assert model.d.tolist()[1:] == [0.0] * 4
    assert result.std[0]["cx"] == 0 and result.std[0]["k2"] == 0 and result.std[0]["fx"] > 0


def test_too_few_views() -> None:
    observed, _ = board_views([true_model()], 4)
    with pytest.raises(ProcessorError, match="too few good views"):
        calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())


def test_threshold_grows_slowly_with_the_data() -> None:
    assert threshold_sigma(10) == 3.0
    assert 4.8 < threshold_sigma(75_000) < 5.0
    # one false rejection expected in two data sets of pure noise
    n = 10_000
    assert n * math.exp(-threshold_sigma(n) ** 2 / 2) == pytest.approx(0.5)


def test_the_model_with_the_tangential_terms_left_out_is_kept_beside() -> None:
    """A lens with a little tangential distortion the test leaves out: the fit with p1 p2 is
    kept beside the result (its difference is stated as uncertainty); with p1 p2 estimated
    nothing is left out."""
    lens = true_model(np.array([-0.2, 0.05, 0.0002, -0.0001, 0.0]))
    observed, _poses = board_views([lens], 12, noise_px=0.2)
    result = calibrate_cameras(POINTS, observed, [(W, H)], CalibrationOptions())
    test = result.tangential_tests[0]
    assert test is not None and not test.estimated
    (richer,) = result.left_out_models
    assert richer is not None and result.models[0].d[2] == 0.0 and richer.d[2] != 0.0
    assert abs(richer.fx - result.models[0].fx) < 5.0
    given = calibrate_cameras(POINTS, observed, [(W, H)],
                              CalibrationOptions(tangential="estimate"))
    assert given.left_out_models == [None]
