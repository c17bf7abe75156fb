"""``camlog check``: whether a log's calibration still fits its images, window by window.

Each window of ``window_s`` seconds (from the log's start) gets, per stereo pair, the
vertical disparity of the features matched across the rectified pair (``vertical_error_px``,
the median of its absolute value) and the right camera's rotation relative to the left that
explains it (``pitch_deg``, ``roll_deg`` and their angle ``rotation_deg``), and per camera
with a board in view, the board's reprojection error (``reprojection_px``, the median over
its views, each view's pose fitted as ``calibrate --check`` does). How windows are flagged:
:mod:`camlog.check.series`.

A log's verdict is ``drifted`` (a window of a check flagged), ``not judged`` (a check that
could not judge it: too few windows with a value, or nothing checkable) or ``clean``; the
command's exit status is that of its worst log (:func:`exit_status`).
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
from processors.drift import PairMatches, StereoMatcher
from replay.camera import CameraModel
from replay.formats import open_reader

from ..errors import InputError
from ..requests.check import CheckRequest
from .cameras import Checkable, Unchecked, checkable
from .samples import samples
from .series import NOISE_SIGMAS, CheckOptions, Series, board_series, stereo_series

__all__ = ["EXIT_DRIFTED", "EXIT_NOT_JUDGED", "NOISE_SIGMAS", "CheckOptions", "LogCheck",
           "Series", "check_drift", "exit_status", "options_of"]

#: exit status of ``camlog check`` when a log drifted (errors exit with 1, usage with 2)
EXIT_DRIFTED = 3
#: exit status when no log drifted but one could not be judged
EXIT_NOT_JUDGED = 4
#: a log's verdicts
CLEAN, DRIFTED, NOT_JUDGED = "clean", "drifted", "not judged"


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

    @property
    def verdict(self) -> str:
        """``drifted``, ``not judged`` or ``clean``."""
        if any(any(s.flagged) for s in self.series):
            return DRIFTED
        if not self.series or any(s.unjudged for s in self.series):
            return NOT_JUDGED
        return CLEAN

    def drifted_from_s(self) -> float | None:
        """When the first flagged window starts (s from the log's start); None if none."""
        starts = [self.span(s.flagged.index(True))[0] for s in self.series if any(s.flagged)]
        return min(starts, default=None)

    def summary(self) -> str:
        """One line: clean, drifted (which camera, from when, by how much), or not judged
        and why."""
        verdict = self.verdict
        if verdict == DRIFTED:
            return f"{self.log}: drifted: " + "; ".join(
                _drift(self, s) for s in self.series if any(s.flagged))
        if verdict == NOT_JUDGED:
            if not self.series:
                return (f"{self.log}: not judged: nothing checkable "
                        f"({'; '.join(_why(u) for u in self.unchecked)})")
            return f"{self.log}: not judged (" + "; ".join(
                f"{s.camera}: {s.unjudged or 'clean'}" for s in self.series) + ")"
        names = ", ".join(s.camera for s in self.series)
        return f"{self.log}: clean ({names}; {self.windows} windows of {self.window_s:g} s)"


def exit_status(checks: list[LogCheck]) -> int:
    """0 when every log is clean, ``EXIT_DRIFTED`` when one drifted, else
    ``EXIT_NOT_JUDGED`` (a log could not be judged)."""
    verdicts = {c.verdict for c in checks}
    if DRIFTED in verdicts:
        return EXIT_DRIFTED
    return EXIT_NOT_JUDGED if NOT_JUDGED in verdicts else 0


def _drift(check: LogCheck, series: Series) -> str:
    """Which camera drifted, from when and by how much (medians over its flagged windows)."""
    start = check.span(series.flagged.index(True))[0]
    limit = f"(limit {series.limit:.3g})"
    if series.kind == "stereo":
        how = (f"rotated {_flagged_median(series, 'rotation_deg'):.3f}° relative to its "
               f"partner (pitch {_flagged_median(series, 'pitch_deg'):+.3f}°, roll "
               f"{_flagged_median(series, 'roll_deg'):+.3f}°), ")
        first = series.values[series.metric][series.flagged.index(True)]
        how += (f"vertical error {_flagged_median(series, series.metric):.2f} px {limit}"
                if series.metric == "vertical_error_px" else
                f"{first:.3g} sigmas from the calibration {limit}, vertical error "
                f"{_flagged_median(series, 'vertical_error_px'):.2f} px")
    else:
        how = f"{series.metric} {_flagged_median(series, series.metric):.3g} {limit}"
    return f"{series.camera} from {start:g} s, {how}"


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


def check_drift(log: Path | str, options: CheckOptions,
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
    series = [stereo_series(c, [w.matches for w in windows], options.threshold)
              if c.kind == "stereo" else
              board_series(c, [w.reprojection_px for w in windows], options.threshold)
              for c, windows in zip(checks, seen, strict=True)]
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


def options_of(request: CheckRequest) -> CheckOptions:
    """The check's options a request asks for (the board made from ``size``, ``square``,
    ``pattern``)."""
    from processors.calibration.board import make_board

    board = make_board(request.size, request.square, request.pattern) \
        if request.size is not None and request.square is not None else None
    return CheckOptions(window_s=request.window, rate_hz=request.rate, board=board,
                        calibration=request.calibration, cameras=list(request.camera),
                        threshold=request.threshold)
