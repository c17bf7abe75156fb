"""From what a check saw in each window to its metrics, its limit and its flagged windows.

A stereo pair's windows are flagged by ``rotation_sigmas``: the right camera's rotation
relative to the left (pitch and roll, fitted to the window's vertical disparities) measured
from the calibration (no rotation) in noise sigmas, ``hypot(pitch / s_pitch, roll / s_roll)``,
each axis's sigma the window's own standard error combined with the log's window-to-window
noise of that axis (:func:`processors.drift.window_noise`, which one drift cannot move) and
the calibration's rotation uncertainty. A window is flagged beyond ``NOISE_SIGMAS``. A
camera with a board in view is flagged by its reprojection error beyond its median over the
windows plus ``NOISE_SIGMAS`` sigmas of the same noise. ``threshold`` replaces the limit
with a fixed one: the vertical error (px) of a pair, the reprojection error (px) of a board.
A moving rig also shows the offset between its cameras' stamps, fitted beside the rotation
(:mod:`processors.drift`); when enough windows show it, a second series of the pair
(``offset``) flags the windows from where it changed (:func:`offset_series`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from processors.calibration.board import Board
from processors.drift import MAD_TO_SIGMA, PairMatches, fit_rotation, window_noise
from replay.messages import F64

from .cameras import Checkable

__all__ = ["MIN_WINDOWS", "NOISE_SIGMAS", "CheckOptions", "Series", "board_series",
           "drift_sigmas", "noise_scale", "offset_series", "stereo_series"]

#: a window is flagged this many noise sigmas beyond a calibrated window's value
NOISE_SIGMAS = 5.0
#: windows with a value needed to measure the noise (fewer: not judged without a threshold)
MIN_WINDOWS = 3
#: the least error of a window's rotation, as the vertical disparity it makes (px): the
#: fit's statistical error alone falls with the number of matches, but no feature is
#: located better than a few hundredths of a pixel (a thousandth of a degree at 640x480)
MIN_ERROR_PX = 0.02


@dataclass(frozen=True)
class CheckOptions:
    """How a log is checked: window length, frames looked at per second, the board (None:
    stereo pairs only), the calibration (None: the log's camera_info), the cameras (empty:
    every one) and a fixed limit that replaces the measured one (px: a pair's vertical
    error, a board's reprojection error)."""

    window_s: float = 2.0
    rate_hz: float = 5.0
    board: Board | None = None
    calibration: Path | None = None
    cameras: list[str] = field(default_factory=list)
    threshold: float | None = None


@dataclass
class Series:
    """One check's metrics per window: ``values[metric]`` ``(W,)`` (NaN where a window had
    nothing to measure), the metric its windows are flagged by, its limit and the flags;
    ``unjudged`` says why the check could not judge the log (empty when it could)."""

    camera: str
    kind: str
    values: dict[str, list[float]]
    metric: str
    limit: float
    flagged: list[bool]
    unjudged: str = ""


def _unjudged(values: list[float], threshold: float | None, nothing: str) -> str:
    """Why a metric's windows cannot be judged: none has a value, or (without a threshold)
    too few to measure their noise; empty when they can."""
    measured = sum(math.isfinite(v) for v in values)
    if measured == 0:
        return nothing
    if threshold is None and measured < MIN_WINDOWS:
        return (f"{measured} window{'s' if measured > 1 else ''} with a value, "
                f"{MIN_WINDOWS} needed to measure the noise (a longer log, a shorter "
                "--window or --threshold)")
    return ""


def _flags(values: list[float], limit: float, unjudged: str) -> list[bool]:
    return [not unjudged and math.isfinite(v) and v > limit for v in values]


def board_series(check: Checkable, reprojection_px: list[list[float]],
                 threshold: float | None) -> Series:
    """A board camera's series from each window's views' reprojection errors (px)."""
    values = [float(np.median(w)) if w else math.nan for w in reprojection_px]
    within = [float(np.std(w)) / math.sqrt(len(w)) for w in reprojection_px if len(w) > 1]
    sigma = max(window_noise(np.asarray(values)), float(np.median(within)) if within else 0.0)
    finite = [v for v in values if math.isfinite(v)]
    centre = float(np.median(finite)) if finite else 0.0
    limit = threshold if threshold is not None else centre + NOISE_SIGMAS * sigma
    unjudged = _unjudged(values, threshold, "the board was not found in any window")
    return Series(check.name, "board", {"reprojection_px": values,
                                        "views": [float(len(w)) for w in reprojection_px]},
                  "reprojection_px", limit, _flags(values, limit, unjudged), unjudged)


def stereo_series(check: Checkable, matches: list[list[PairMatches]],
                  threshold: float | None) -> Series:
    """A stereo pair's series from each window's matches (one entry per pair of images)."""
    right = check.infos[1]
    names = ("vertical_error_px", "rotation_deg", "pitch_deg", "roll_deg", "pitch_std_deg",
             "roll_std_deg", "matches", "offset_ms", "offset_std_ms")
    metrics: dict[str, list[float]] = {name: [] for name in names}
    for window in matches:
        joined = _joined(window)
        views = np.repeat(np.arange(len(window)), [len(m.dy_px) for m in window])
        fit = fit_rotation(joined, p_rect=right.p, rect_from_right=right.r,
                           views=views.astype(np.int64))
        dy = joined.dy_px
        for name, value in zip(names, (
                float(np.median(np.abs(dy))) if dy.size else math.nan, fit.angle_deg,
                math.degrees(fit.pitch_rad), math.degrees(fit.roll_rad),
                math.degrees(fit.pitch_std_rad), math.degrees(fit.roll_std_rad),
                float(fit.matches), 1000 * fit.offset_s, 1000 * fit.offset_std_s),
                strict=True):
            metrics[name].append(value)
    unjudged = _unjudged(metrics["rotation_deg"], threshold,
                         "no window had enough features matched across the pair")
    if threshold is not None:
        return Series(check.name, "stereo", metrics, "vertical_error_px", threshold,
                      _flags(metrics["vertical_error_px"], threshold, unjudged), unjudged)
    floor_deg = math.degrees(MIN_ERROR_PX / float(right.p[1, 1]))
    metrics["drift_sigmas"], onset = drift_sigmas(metrics, check.rotation_std_deg,
                                                  floor_deg)
    flagged = [not unjudged and onset is not None and index >= onset
               for index in range(len(matches))]
    return Series(check.name, "stereo", metrics, "drift_sigmas", NOISE_SIGMAS, flagged,
                  unjudged)


def _joined(window: list[PairMatches]) -> PairMatches:
    """A window's matches in one set (their speeds and stamp gaps only when every pair of
    images of the window has them)."""
    timed = bool(window) and all(m.row_speed_px_s is not None for m in window)
    return PairMatches(
        np.concatenate([m.left_px for m in window] or [np.zeros((0, 2))]),
        np.concatenate([m.right_px for m in window] or [np.zeros((0, 2))]),
        np.concatenate([m.row_speed_px_s for m in window
                        if m.row_speed_px_s is not None]) if timed else None,
        np.concatenate([m.stamp_gap_s for m in window
                        if m.stamp_gap_s is not None]) if timed else None,
        np.concatenate([m.row_acceleration_px_s2 for m in window
                        if m.row_acceleration_px_s2 is not None]) if timed
        and all(m.row_acceleration_px_s2 is not None for m in window) else None)


def offset_series(pair: Series) -> list[Series]:
    """The offset between a pair's stamps over its windows, flagged from the window where it
    changed (a driver restarted): for each window ``k`` the step between the mean offset of
    the windows before it and of those from it on, in sigmas (each window weighted by its
    standard error times :func:`noise_scale`), flagged from the largest step beyond
    ``NOISE_SIGMAS``. None when fewer than ``MIN_WINDOWS`` windows show the offset (the rig
    stood still, or moved only along the rows)."""
    offsets = np.array(pair.values["offset_ms"], dtype=np.float64)
    std = np.array(pair.values["offset_std_ms"], dtype=np.float64)
    usable = np.isfinite(offsets) & np.isfinite(std) & (std > 0)
    if usable.sum() < MIN_WINDOWS:
        return []
    sigma = noise_scale(offsets, std) * std
    weight = np.where(usable, 1.0 / np.where(usable, sigma, 1.0) ** 2, 0.0)
    weighted = np.where(usable, offsets, 0.0) * weight
    before_w, before_s = np.cumsum(weight) - weight, np.cumsum(weighted) - weighted
    after_w = np.cumsum(weight[::-1])[::-1]
    after_s = np.cumsum(weighted[::-1])[::-1]
    with np.errstate(invalid="ignore", divide="ignore"):
        steps = np.abs(after_s / after_w - before_s / before_w) \
            / np.sqrt(1.0 / after_w + 1.0 / before_w)
    steps = np.where(usable & (before_w > 0) & (after_w > 0), steps, np.nan)
    onset = int(np.nanargmax(steps)) if np.any(np.isfinite(steps)) \
        and np.nanmax(steps) > NOISE_SIGMAS else None
    values = {"offset_ms": pair.values["offset_ms"], "offset_std_ms": pair.values["offset_std_ms"],
              "offset_change_sigmas": [float(v) for v in steps]}
    flagged = [onset is not None and index >= onset for index in range(len(offsets))]
    return [Series(pair.camera, "offset", values, "offset_change_sigmas", NOISE_SIGMAS,
                   flagged)]


def drift_sigmas(metrics: dict[str, list[float]], calibration_std_deg: float,
                 floor_deg: float) -> tuple[list[float], int | None]:
    """For each window ``k`` the mean rotation of windows ``k..`` (to the log's end) from
    the calibration, in its sigmas, leaving out the one window of them that is furthest
    from the calibration ``(W,)`` (NaN where window ``k`` has no value), and the window
    where it peaks beyond ``NOISE_SIGMAS`` (None: nowhere).

    Each axis's windows are weighted by ``1 / (scale * std)²``, their standard errors (at
    least ``floor_deg``) times :func:`noise_scale`; the calibration's uncertainty is common
    to every window, so it bounds the mean's sigma from below however many windows there
    are. A window whose features were matched wrongly (a board seen edge-on) can be far off
    on its own; a drift lasts, so the windows after its first one show it without it: the
    log's last window alone is never a drift."""
    angles = np.array([metrics["pitch_deg"], metrics["roll_deg"]])  # (2, W)
    std = np.maximum(np.array([metrics["pitch_std_deg"], metrics["roll_std_deg"]]), floor_deg)
    sigma = np.array([noise_scale(a, s) for a, s in zip(angles, std, strict=True)])[:, None] \
        * std
    usable = np.isfinite(angles) & np.isfinite(sigma)
    weight = np.where(usable, 1.0 / np.where(usable, sigma, 1.0) ** 2, 0.0)
    weighted = np.where(usable, angles, 0.0) * weight
    # sums from each window to the end, and the furthest window of each tail
    tail_weight = np.cumsum(weight[:, ::-1], axis=1)[:, ::-1]
    tail_sum = np.cumsum(weighted[:, ::-1], axis=1)[:, ::-1]
    furthest = _furthest_from(np.sum(weighted * np.where(usable, angles, 0.0), axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        kept_weight = tail_weight - weight[:, furthest]
        kept_sum = tail_sum - weighted[:, furthest]
        squares = np.sum((kept_sum / kept_weight) ** 2
                         / (1.0 / kept_weight + calibration_std_deg**2), axis=0)
    measured = np.isfinite(np.asarray(metrics["rotation_deg"]))
    sigmas = np.where(measured, np.sqrt(np.nan_to_num(squares)), np.nan)
    if not measured.any() or not np.nanmax(sigmas) > NOISE_SIGMAS:
        return [float(v) for v in sigmas], None
    return [float(v) for v in sigmas], int(np.nanargmax(sigmas))


def _furthest_from(chi_squares: F64) -> npt.NDArray[np.int64]:
    """For each window ``k`` the window ``i >= k`` of the largest value ``(W,)``."""
    furthest = np.zeros(len(chi_squares), np.int64)
    best = len(chi_squares) - 1
    for index in range(len(chi_squares) - 1, -1, -1):
        if chi_squares[index] > chi_squares[best]:
            best = index
        furthest[index] = best
    return furthest


def noise_scale(values: F64, std: F64) -> float:
    """How much the windows' values ``(W,)`` vary beyond their standard errors ``(W,)``: the
    robust sigma of successive differences, each over its two errors combined (NaNs
    skipped), at least 1. Views of one window share errors a window's own fit cannot see
    (a board seen at a slant moves all its features alike); a drift is one step between two
    windows and does not move the estimate."""
    finite = np.isfinite(values) & np.isfinite(std) & (std > 0)
    value, error = values[finite], std[finite]
    if value.size < 2:
        return 1.0
    steps = np.diff(value) / np.hypot(error[1:], error[:-1])
    return max(1.0, MAD_TO_SIGMA * float(np.median(np.abs(steps))))
