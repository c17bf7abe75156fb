"""The offset between a calibrated pair's stamps from natural features of a moving rig.

A calibrated pair, rectified, sees every scene point on the same row in both images when
both expose at the same instant. When the right camera's frame was exposed ``tau`` seconds
after the left one's, a point moving down the image at ``v`` px/s sits ``v tau`` lower in
the right image: the epipolar error of a moving rig grows with the exposure offset. Each
feature matched from a right frame into the left frame nearest its stamp is tracked
through the left frames around it (:data:`STENCIL` frames, Lucas-Kanade, checked forwards
and back), so that its row is known at any time between them (:mod:`.interpolation`); the
offset is the time shift that puts every right row on its feature's left row at the right
frame's stamp less the offset, with the pair's rotation (pitch and roll about the
rectified axes, the terms of :mod:`processors.drift`) fitted beside it, should the
calibration be a little off.

Only motion across the rows carries the offset (pitch, a vertical move; the rows of a
horizontal rig): a rig that stands still, or only pans along the rows, does not show it.
It reaches offsets up to about ``(STENCIL // 2) - 0.5`` frame periods from the stamps' own
pairing (50 ms at 30 Hz).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from replay.messages import F64

from .estimate import CLUSTER_FRAMES, NotObservableError, OffsetEstimate, robust_fit
from .interpolation import lagrange_weights

__all__ = ["STENCIL", "FeaturePair", "estimate_feature_offset", "track_rows"]

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]

#: left frames a feature is tracked through, the one matched in the middle
STENCIL = 5
#: a track is kept when following it back returns within this (px)
BACK_PX = 0.3
LK_WINDOW = (15, 15)
LK_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 0.01)
#: a frame carries the offset when its features move across the rows at least this fast
#: (px per second, RMS over them): a pixel per frame at 30 Hz
MOVING_PX_S = 30.0
MIN_MOVING_FRAMES = 10
#: a standard deviation above this (s) is no measurement
MAX_STD_S = 0.005
#: a pair's features: at least this many
MIN_FEATURES = 8
TOLERANCE = np.array([1e-8, 1e-9, 1e-9])


@dataclass(frozen=True)
class FeaturePair:
    """Features of one right frame and the left frames around it, in the rectified images:
    the left frames' times ``left_times_s`` ``(K,)``, each feature's row in each of them
    ``left_rows_px`` ``(M, K)``, the right frame's time ``right_time_s`` and its features
    ``right_px`` ``(M, 2)`` (times in each camera's own stamps, s from a common origin)."""

    left_times_s: F64
    left_rows_px: F64
    right_time_s: float
    right_px: F64


def track_rows(grays: list[np.ndarray], centre: int, points_px: F64) -> tuple[F64, B8]:
    """Where raw pixels ``points_px`` ``(M, 2)`` of frame ``grays[centre]`` are in each of
    the ``grays`` ``(H, W)`` uint8 (Lucas-Kanade), ``(M, K, 2)``, and which features were
    followed in every frame ``(M,)`` (tracked there and back within :data:`BACK_PX`)."""
    count = len(points_px)
    out = np.full((count, len(grays), 2), np.nan)
    out[:, centre] = points_px
    kept = np.ones(count, bool)
    start = np.ascontiguousarray(points_px, dtype=np.float32).reshape(-1, 1, 2)
    for index, gray in enumerate(grays):
        if index == centre or not count:
            continue
        there, status, _ = cv2.calcOpticalFlowPyrLK(
            grays[centre], gray, start, start.copy(), winSize=LK_WINDOW, maxLevel=2,
            criteria=LK_CRITERIA, flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        there = np.asarray(there, dtype=np.float32)
        back, status_back, _ = cv2.calcOpticalFlowPyrLK(
            gray, grays[centre], there, start.copy(), winSize=LK_WINDOW, maxLevel=2,
            criteria=LK_CRITERIA, flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        kept &= (np.asarray(status).reshape(-1) == 1) \
            & (np.asarray(status_back).reshape(-1) == 1) \
            & (np.linalg.norm((np.asarray(back) - start).reshape(-1, 2), axis=1) <= BACK_PX)
        out[:, index] = there.reshape(-1, 2)
    return out, kept


@dataclass(frozen=True)
class _FeatureFit:
    offset_s: float
    rotation: F64  # pitch, roll (rad) about the rectified axes


def _advance(state: _FeatureFit, step: F64) -> _FeatureFit:
    return _FeatureFit(state.offset_s + float(step[0]), state.rotation + step[1:])


def estimate_feature_offset(pairs: list[FeaturePair], *, p_rect: F64) -> OffsetEstimate:
    """How much later the right camera stamps an instant than the left one, from features
    of a moving rig (see the module's text); ``p_rect`` ``(3, 4)`` is the rectified right
    camera's projection (its calibration's ``P``). Raises :class:`NotObservableError` when the
    features do not move across the rows or too few are matched."""
    if p_rect.shape != (3, 4):
        raise ValueError(f"p_rect must be (3, 4), got {p_rect.shape}")
    usable = [p for p in pairs if len(p.right_px) >= MIN_FEATURES]
    if len(usable) < MIN_MOVING_FRAMES:
        raise NotObservableError(f"features matched across the pair in {len(usable)} frames "
                            f"(need {MIN_MOVING_FRAMES}): no shared view, or no texture")
    f_px, cx, cy = float(p_rect[1, 1]), float(p_rect[0, 2]), float(p_rect[1, 2])
    sizes = [len(p.right_px) for p in usable]
    rows = np.concatenate([p.left_rows_px for p in usable])  # (M, K)
    times = np.concatenate([np.repeat(p.left_times_s[None], len(p.right_px), axis=0)
                            for p in usable])
    right = np.concatenate([p.right_px for p in usable])
    right_time = np.repeat([p.right_time_s for p in usable], sizes)
    frame = np.repeat(np.arange(len(usable)), sizes)
    x, y = (right[:, 0] - cx) / float(p_rect[0, 0]), (right[:, 1] - cy) / f_px
    design = f_px * np.column_stack([1.0 + y * y, -x])
    origin = times.mean(axis=1, keepdims=True)
    period = float(np.median(np.diff(usable[0].left_times_s)))

    def speeds(state: _FeatureFit) -> tuple[F64, F64]:
        weights, derivative = lagrange_weights(times - origin,
                                               right_time - state.offset_s - origin[:, 0])
        return np.sum(weights * rows, axis=1), np.sum(derivative * rows, axis=1)

    def linearize(state: _FeatureFit) -> tuple[F64, F64]:
        row, speed = speeds(state)
        residual = right[:, 1] - row - design @ state.rotation
        return residual, np.column_stack([speed, -design])

    clusters = np.floor(right_time / (CLUSTER_FRAMES * period)).astype(np.int64)
    fit = robust_fit(linearize, _advance, _FeatureFit(0.0, np.zeros(2)), clusters=clusters,
                     tolerance=TOLERANCE)
    state = fit.state
    _, speed = speeds(state)
    moving_rms = np.sqrt(np.bincount(frame[fit.inliers], speed[fit.inliers] ** 2,
                                     minlength=len(usable))
                         / np.maximum(np.bincount(frame[fit.inliers], minlength=len(usable)),
                                      1))
    moving = int((moving_rms >= MOVING_PX_S).sum())
    std = math.sqrt(max(float(fit.covariance[0, 0]), 0.0))
    if moving < MIN_MOVING_FRAMES or not std <= MAX_STD_S:
        raise NotObservableError(
            f"the features hardly move across the rows ({moving} of {len(usable)} frames "
            f"move them {MOVING_PX_S:g} px/s or more): a rig that stands still, or moves "
            "only along the rows, does not show the offset")
    used = fit.residuals[fit.inliers]
    return OffsetEstimate(state.offset_s, std, moving, len(usable),
                          math.sqrt(float(np.mean(used ** 2))), "features")
