"""``camlog check``: whether a log's calibration still fits its images, window by window.

Each window of ``window_s`` seconds (from the log's start) gets, per stereo pair, the
vertical disparity of the features matched across the rectified pair (``vertical_error_px``,
the median of its absolute value) and the right camera's rotation relative to the left that
explains it (``pitch_deg``, ``roll_deg`` and their angle ``rotation_deg``), and per camera
with a board in view, the board's reprojection error (``reprojection_px``, the median over
its views, each view's pose fitted as ``calibrate --check`` does).

The limit a window is flagged above comes from the log itself and the calibration: the
noise ``sigma`` of the metric from window to window (:func:`processors.drift.window_noise`,
which one drift cannot move), at least the statistical error of one window's fit, combined
with the calibration's own rotation uncertainty; a pair's rotation is flagged beyond
``NOISE_SIGMAS`` such sigmas from zero, a board's error beyond that above its median.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from processors.calibration.board import Board
from processors.calibration.targets import find_board
from processors.calibration.view_fit import fit_view
from processors.drift import PairMatches, StereoMatcher, fit_rotation, window_noise
from replay.camera import CameraModel
from replay.formats import open_reader

from ..errors import InputError
from .cameras import Checkable, Unchecked, checkable
from .samples import samples

__all__ = ["NOISE_SIGMAS", "CheckOptions", "LogCheck", "Series", "check_log"]

#: a window is flagged this many noise sigmas beyond a calibrated window's value
NOISE_SIGMAS = 5.0
#: windows with a value needed to measure the noise (fewer: no limit without --threshold)
MIN_WINDOWS = 3


@dataclass(frozen=True)
class CheckOptions:
    """How a log is checked: window length, frames looked at per second, the board (None:
    stereo pairs only), the calibration (None: the log's camera_info), the cameras (empty:
    every one) and a limit that replaces the measured one (per flagged metric's unit)."""

    window_s: float = 2.0
    rate_hz: float = 5.0
    board: Board | None = None
    calibration: Path | None = None
    cameras: list[str] = field(default_factory=list)
    threshold: float | None = None


@dataclass
class Series:
    """One check's metrics per window: ``values[metric]`` ``(W,)`` (NaN where a window had
    nothing to measure), the metric its windows are flagged by, its limit and the flags."""

    camera: str
    kind: str
    values: dict[str, list[float]]
    metric: str
    limit: float
    flagged: list[bool]


@dataclass
class LogCheck:
    """Everything ``check`` found in one log."""

    log: str
    window_s: float
    windows: int
    series: list[Series]
    unchecked: list[Unchecked]

    def span(self, index: int) -> tuple[float, float]:
        """Start and end (s from the log's start) of window ``index``."""
        return index * self.window_s, (index + 1) * self.window_s

    def summary(self) -> str:
        """One line: clean, or which camera drifted from when and by how much."""
        if not self.series:
            return f"{self.log}: not checkable ({'; '.join(_why(u) for u in self.unchecked)})"
        drifted = []
        for s in self.series:
            if not any(s.flagged):
                continue
            first = s.flagged.index(True)
            how = f"{s.metric} {_flagged_median(s, s.metric):.3g} (limit {s.limit:.3g})"
            if s.kind == "stereo":
                how = (f"rotated {_flagged_median(s, 'rotation_deg'):.3f}° relative to its "
                       f"partner (pitch {_flagged_median(s, 'pitch_deg'):+.3f}°, roll "
                       f"{_flagged_median(s, 'roll_deg'):+.3f}°), vertical error "
                       f"{_flagged_median(s, s.metric):.2f} px (limit {s.limit:.2f} px)")
            drifted.append(f"{s.camera} from {self.span(first)[0]:g} s, {how}")
        if not drifted:
            names = ", ".join(s.camera for s in self.series)
            if any(math.isinf(s.limit) for s in self.series):
                return (f"{self.log}: not judged ({names}: fewer than {MIN_WINDOWS} windows "
                        f"of {self.window_s:g} s to measure the noise; give --threshold or a "
                        "shorter --window)")
            return f"{self.log}: clean ({names}; {self.windows} windows of {self.window_s:g} s)"
        return f"{self.log}: drifted: " + "; ".join(drifted)


def _flagged_median(series: Series, metric: str) -> float:
    """The median of a metric over the flagged windows (NaN: none has a value)."""
    values = [v for v, f in zip(series.values[metric], series.flagged, strict=True)
              if f and math.isfinite(v)]
    return float(np.median(values)) if values else math.nan


def _why(unchecked: Unchecked) -> str:
    return f"{unchecked.namespace}: {unchecked.reason}"


@dataclass
class _Window:
    """What one check saw in one window."""

    matches: list[PairMatches] = field(default_factory=list)
    reprojection_px: list[float] = field(default_factory=list)


def check_log(log: Path | str, options: CheckOptions,
              on_window: Callable[[], None] | None = None) -> LogCheck:
    """Check one log (a path or an object-storage URI)."""
    with open_reader(log) as reader:
        checks, unchecked = checkable(reader, cameras=options.cameras, board=options.board,
                                      calibration=options.calibration)
        start_ns = reader.start_ns or 0
        windows = max(1, math.ceil(((reader.end_ns or start_ns) - start_ns) * 1e-9
                                   / options.window_s - 1e-9))
        seen = [[_Window() for _ in range(windows)] for _ in checks]
        matchers = [StereoMatcher(*c.infos) if c.kind == "stereo" else None for c in checks]
        for sample in samples(reader, checks, rate_hz=options.rate_hz):
            index = min(windows - 1, int((sample.log_time_ns - start_ns) * 1e-9
                                         / options.window_s))
            window = seen[sample.check][index]
            matcher = matchers[sample.check]
            if matcher is not None:
                window.matches.append(matcher.match(*sample.grays))
            else:
                _board_view(window, sample.grays[0], checks[sample.check], options.board)
            if on_window is not None:
                on_window()
    series = [_series(c, w, options) for c, w in zip(checks, seen, strict=True)]
    return LogCheck(str(log), options.window_s, windows, series, unchecked)


def _board_view(window: _Window, gray: np.ndarray, check: Checkable, board: Board | None
                ) -> None:
    assert board is not None
    model = CameraModel.from_camera_info(check.infos[0])
    if gray.shape != (model.height, model.width):
        raise InputError(f"{check.name}: images are {gray.shape[1]}x{gray.shape[0]}, the "
                         f"calibration is for {model.width}x{model.height}")
    detection = find_board(gray, board, model)
    if detection is None or not detection.accepted:
        return
    fit = fit_view(detection.corners_px, model, board.points_in_board()[detection.ids])
    if fit is not None:
        window.reprojection_px.append(fit.rms_px)


def _unmeasured(values: list[float]) -> float:
    """Infinity (no limit) when too few windows have a value to measure the noise, else 0."""
    return math.inf if sum(math.isfinite(v) for v in values) < MIN_WINDOWS else 0.0


def _series(check: Checkable, windows: list[_Window], options: CheckOptions) -> Series:
    if check.kind == "stereo":
        return _stereo_series(check, windows, options)
    values = [float(np.median(w.reprojection_px)) if w.reprojection_px else math.nan
              for w in windows]
    within = [float(np.std(w.reprojection_px)) / math.sqrt(len(w.reprojection_px))
              for w in windows if len(w.reprojection_px) > 1]
    sigma = max(window_noise(np.asarray(values)), float(np.median(within)) if within else 0.0)
    finite = [v for v in values if math.isfinite(v)]
    centre = float(np.median(finite)) if finite else 0.0
    limit = options.threshold if options.threshold is not None \
        else _unmeasured(values) or centre + NOISE_SIGMAS * sigma
    return Series(check.name, "board", {"reprojection_px": values,
                                        "views": [float(len(w.reprojection_px)) for w in windows]},
                  "reprojection_px", limit, [bool(math.isfinite(v) and v > limit) for v in values])


def _stereo_series(check: Checkable, windows: list[_Window], options: CheckOptions) -> Series:
    right = check.infos[1]
    metrics: dict[str, list[float]] = {m: [] for m in (
        "vertical_error_px", "rotation_deg", "pitch_deg", "roll_deg", "matches")}
    clean = []
    for window in windows:
        joined = PairMatches(
            np.concatenate([m.left_px for m in window.matches] or [np.zeros((0, 2))]),
            np.concatenate([m.right_px for m in window.matches] or [np.zeros((0, 2))]))
        fit = fit_rotation(joined, p_rect=right.p, rect_from_right=right.r)
        dy = joined.dy_px
        metrics["vertical_error_px"].append(float(np.median(np.abs(dy))) if dy.size
                                            else math.nan)
        metrics["rotation_deg"].append(fit.angle_deg)
        metrics["pitch_deg"].append(math.degrees(fit.pitch_rad))
        metrics["roll_deg"].append(math.degrees(fit.roll_rad))
        metrics["matches"].append(float(fit.matches))
        if math.isfinite(fit.clean_px):
            clean.append(fit.clean_px)
    errors = np.asarray(metrics["vertical_error_px"])
    # a calibrated window's vertical error: what is left once the rotation is fitted
    centre = float(np.median(clean)) if clean else 0.0
    calibration_px = math.radians(check.rotation_std_deg) * float(right.p[1, 1])
    limit = options.threshold if options.threshold is not None \
        else _unmeasured(metrics["vertical_error_px"]) \
        or centre + NOISE_SIGMAS * math.hypot(window_noise(errors), calibration_px)
    return Series(check.name, "stereo", metrics, "vertical_error_px", limit,
                  [bool(math.isfinite(v) and v > limit) for v in errors])
