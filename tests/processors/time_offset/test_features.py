"""The offset between a calibrated pair's stamps from features of a moving rig (synthetic)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from processors.time_offset import NotObservableError
from processors.time_offset.features import (
    STENCIL,
    FeaturePair,
    estimate_feature_offset,
    track_rows,
)

F_PX, CX, CY = 400.0, 319.5, 239.5
P_RECT = np.array([[F_PX, 0.0, CX, -F_PX * 0.06], [0.0, F_PX, CY, 0.0], [0.0, 0.0, 1.0, 0.0]])
PERIOD_S = 1 / 30


def _rows(points: np.ndarray, pitch_rad: float, *, baseline_m: float = 0.0) -> np.ndarray:
    """Rectified pixels ``(M, 2)`` of points ``(M, 3)`` seen by a camera of the rig pitched
    by ``pitch_rad`` about its x axis (``baseline_m`` along it)."""
    c, s = math.cos(pitch_rad), math.sin(pitch_rad)
    turned = points @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T
    turned[:, 0] -= baseline_m
    return np.column_stack([F_PX * turned[:, 0] / turned[:, 2] + CX,
                            F_PX * turned[:, 1] / turned[:, 2] + CY])


def pairs(offset_ms: float, *, amplitude_rad: float = 0.05, frames: int = 90,
          noise_px: float = 0.05, seed: int = 0) -> list[FeaturePair]:
    """A rig nodding (pitch ``amplitude_rad`` at 0.7 Hz) over points 0.5-2 m away, its
    right camera stamping ``offset_ms`` late; both cameras expose at the same instants."""
    rng = np.random.default_rng(seed)
    points = np.column_stack([rng.uniform(-0.6, 0.6, (80, 2)), rng.uniform(0.5, 2.0, 80)])

    def pitch(t: float) -> float:
        return amplitude_rad * math.sin(2 * math.pi * 0.7 * t)

    out = []
    half = STENCIL // 2
    for k in range(half, frames - half):
        times = np.arange(k - half, k + half + 1, dtype=np.float64) * PERIOD_S
        left = np.stack([_rows(points, pitch(t))[:, 1] for t in times], axis=1)
        right = _rows(points, pitch(k * PERIOD_S), baseline_m=0.06)
        out.append(FeaturePair(times, left + rng.normal(0, noise_px, left.shape),
                               k * PERIOD_S + offset_ms / 1000,
                               right + rng.normal(0, noise_px, right.shape)))
    return out


@pytest.mark.parametrize("offset_ms", [0.0, 17.0, -10.0])
def test_a_nodding_rig_shows_the_offset(offset_ms: float) -> None:
    estimate = estimate_feature_offset(pairs(offset_ms), p_rect=P_RECT)
    assert abs(estimate.offset_ms - offset_ms) < 0.1
    assert abs(estimate.offset_ms - offset_ms) < 5 * estimate.std_ms
    assert estimate.method == "features" and estimate.second_from_first is None
    assert estimate.frames > 40


def test_a_rig_standing_still_does_not() -> None:
    with pytest.raises(NotObservableError, match="hardly move across the rows"):
        estimate_feature_offset(pairs(17.0, amplitude_rad=0.0), p_rect=P_RECT)


def test_too_few_matched_frames() -> None:
    few = [FeaturePair(p.left_times_s, p.left_rows_px[:3], p.right_time_s, p.right_px[:3])
           for p in pairs(0.0)]
    with pytest.raises(NotObservableError, match="no shared view, or no texture"):
        estimate_feature_offset(few, p_rect=P_RECT)


def test_features_are_followed_through_the_frames() -> None:
    """A textured image moved down by 0.4 px per frame: each feature's row grows by 0.4."""
    rng = np.random.default_rng(1)
    texture = cv2.GaussianBlur(rng.uniform(0, 255, (160, 200)).astype(np.float32), (0, 0), 2.0)
    grays = [cv2.warpAffine(texture, np.array([[1.0, 0, 0], [0, 1.0, 0.4 * k]]), (200, 160))
             .astype(np.uint8) for k in range(-2, 3)]
    points = np.array([[60.0, 50.0], [120.0, 90.0], [150.0, 70.0]])
    tracked, kept = track_rows(grays, 2, points)
    assert kept.all()
    np.testing.assert_allclose(tracked[:, :, 1] - points[:, 1:2],
                               np.tile(0.4 * np.arange(-2, 3), (3, 1)), atol=0.05)
    np.testing.assert_allclose(tracked[:, :, 0], np.tile(points[:, :1], (1, 5)), atol=0.05)
