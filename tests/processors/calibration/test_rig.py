"""Transforms between two cameras of a rig and their covariance from the joint solve."""

from __future__ import annotations

import numpy as np

from processors.calibration.joint import calibrate_cameras
from processors.calibration.options import CalibrationOptions
from processors.calibration.rig import angle_deg, relative_pose
from processors.calibration.rotation import rotation_vectors

from .synthetic import H, W, pose, true_model
from .test_joint import POINTS, RIGHT_FROM_LEFT, board_views

FAR = pose(np.array([0.02, -0.05, 0.01]), np.array([-0.06, 0.004, 0.002]))


def test_pair_transform_and_covariance_follow_from_the_reference_ones() -> None:
    placements = [np.eye(4), RIGHT_FROM_LEFT, FAR]
    observed, _ = board_views([true_model()] * 3, 24, seed=8, placements=placements)
    result = calibrate_cameras(POINTS, observed, [(W, H)] * 3, CalibrationOptions())
    # from the reference: the solver's own transform and covariance
    transform, covariance = relative_pose(result, 0, 2)
    np.testing.assert_array_equal(transform, result.camera_from_reference[2])
    np.testing.assert_array_equal(covariance, result.rig_covariance[2])
    # between two other cameras: the composed transform, within its covariance of the truth
    transform, covariance = relative_pose(result, 1, 2)
    np.testing.assert_allclose(transform, result.camera_from_reference[2]
                               @ np.linalg.inv(result.camera_from_reference[1]), atol=1e-12)
    truth = FAR @ np.linalg.inv(RIGHT_FROM_LEFT)
    error = np.concatenate([rotation_vectors((transform[:3, :3] @ truth[:3, :3].T)[None])[0],
                            transform[:3, 3] - truth[:3, 3]])
    assert float(error @ np.linalg.solve(covariance, error)) < 4.5 ** 2
    # the reverse pair: the inverse transform, its baseline as uncertain as the forward one
    back, back_covariance = relative_pose(result, 2, 1)
    np.testing.assert_allclose(back @ transform, np.eye(4), atol=1e-12)
    direction = transform[:3, 3] / np.linalg.norm(transform[:3, 3])
    forward_std = np.sqrt(direction @ covariance[3:, 3:] @ direction)
    back_direction = back[:3, 3] / np.linalg.norm(back[:3, 3])
    back_std = np.sqrt(back_direction @ back_covariance[3:, 3:] @ back_direction)
    assert abs(back_std / forward_std - 1) < 1e-6
    assert abs(angle_deg(back[:3, :3]) - angle_deg(transform[:3, :3])) < 1e-9
