"""What ``camlog check`` writes: ``check.csv`` (one row per log, camera, window and
metric), ``report.md``, one PNG per log of its flagged metrics over time and ``check.rrd``
(:mod:`camlog.check.recording`)."""

from __future__ import annotations

import csv
import io
import itertools
import math
from pathlib import Path

import cv2
import numpy as np

from camlog.calibrate.figures import BLACK, BLUE, FONT, GREEN, GREY, RED
from replay.atomic import write_bytes_atomic, write_text_atomic

from .flow import LogCheck, Series
from .recording import entity_names, write_recording

__all__ = ["CSV_COLUMNS", "figure", "write_report"]

CSV_COLUMNS = ("log", "camera", "start_s", "end_s", "metric", "value", "flagged")
WIDTH, HEIGHT, MARGIN = 720, 180, 60
SHADE = (215, 215, 250)
TOP_LIMITS = 4.0


def csv_text(checks: list[LogCheck]) -> str:
    """``check.csv``: every metric of every window (a window's rows share its flag)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for check in checks:
        for series in check.series:
            for index in range(check.windows):
                start, end = check.span(index)
                for metric, values in series.values.items():
                    value = values[index]
                    writer.writerow([check.log, series.camera, f"{start:g}", f"{end:g}", metric,
                                     "" if math.isnan(value) else f"{value:.6g}",
                                     int(series.flagged[index])])
    return out.getvalue()


def figure(check: LogCheck) -> np.ndarray:
    """Each check's metrics per window over time (BGR ``(H, W, 3)`` uint8), its flagged
    windows shaded: a stereo pair's rotation (pitch and roll, degrees) from the
    calibration, or the flagged metric with its limit (dashed red)."""
    panels = [_panel(check, s) for s in check.series] or [_empty(check)]
    return np.vstack(panels)


def _lines(series: Series) -> tuple[list[tuple[str, tuple[int, int, int]]], str]:
    """The metrics a panel draws (with their colours) and its title."""
    if series.metric == "offset_change_sigmas":
        return [("offset_ms", BLUE)], \
            "time offset between the cameras' stamps (ms; right later than left)"
    if series.metric == "drift_sigmas":
        return [("pitch_deg", BLUE), ("roll_deg", GREEN)], \
            "rotation from the calibration (deg): pitch (blue), roll (green)"
    return [(series.metric, BLUE)], series.metric


def _range(values: list[float], limit: float) -> tuple[float, float]:
    """The panel's value range: zero, the values and the limit; values past
    ``TOP_LIMITS`` limits are drawn at the top, so that one drift does not flatten the
    rest."""
    finite = [v for v in values if math.isfinite(v)]
    high = max([*finite, 0.0])
    if math.isfinite(limit):
        high = max(limit, min(high, TOP_LIMITS * limit))
    low = min([*finite, 0.0])
    pad = 0.1 * max(high - low, 1e-9)
    return low - (pad if low < 0 else 0.0), high + pad


def _panel(check: LogCheck, series: Series) -> np.ndarray:
    img = np.full((HEIGHT + 2 * MARGIN, WIDTH + 2 * MARGIN, 3), 255, np.uint8)
    lines, what = _lines(series)
    limited = math.isfinite(series.limit) \
        and series.metric not in ("drift_sigmas", "offset_change_sigmas")
    low, high = _range([v for m, _ in lines for v in series.values[m]],
                       series.limit if limited else math.nan)
    span_s = check.windows * check.window_s

    def x(t_s: float) -> int:
        return int(MARGIN + t_s / span_s * WIDTH)

    def y(value: float) -> int:
        return int(MARGIN + HEIGHT - (min(max(value, low), high) - low) / (high - low) * HEIGHT)

    for index, flagged in enumerate(series.flagged):
        if flagged:
            start, end = check.span(index)
            cv2.rectangle(img, (x(start), MARGIN), (x(end), MARGIN + HEIGHT), SHADE, -1)
    if low < 0:
        cv2.line(img, (MARGIN, y(0.0)), (MARGIN + WIDTH, y(0.0)), GREY, 1)
    for dash in range(MARGIN, MARGIN + WIDTH, 12) if limited else ():
        cv2.line(img, (dash, y(series.limit)), (min(dash + 6, MARGIN + WIDTH),
                                                y(series.limit)), RED, 1)
    for metric, colour in lines:
        points = [(x(sum(check.span(i)) / 2), y(v))
                  for i, v in enumerate(series.values[metric]) if math.isfinite(v)]
        for a, b in itertools.pairwise(points):
            cv2.line(img, a, b, colour, 2, cv2.LINE_AA)
        for p in points:
            cv2.circle(img, p, 3, colour, -1, cv2.LINE_AA)
    cv2.rectangle(img, (MARGIN, MARGIN), (MARGIN + WIDTH, MARGIN + HEIGHT), BLACK, 1)
    for t in range(int(span_s) + 1):
        if t % max(1, int(span_s) // 10) == 0:
            cv2.putText(img, f"{t}", (x(t) - 4, MARGIN + HEIGHT + 16), FONT, 0.4, BLACK, 1,
                        cv2.LINE_AA)
    cv2.putText(img, "s", (MARGIN + WIDTH + 8, MARGIN + HEIGHT + 16), FONT, 0.4, BLACK, 1)
    cv2.putText(img, f"{high:.3g}", (4, MARGIN + 4), FONT, 0.4, GREY, 1, cv2.LINE_AA)
    cv2.putText(img, f"{low:.3g}", (4, MARGIN + HEIGHT), FONT, 0.4, GREY, 1, cv2.LINE_AA)
    if limited:
        cv2.putText(img, f"limit {series.limit:.3g}", (MARGIN + WIDTH - 110,
                                                       y(series.limit) - 6),
                    FONT, 0.4, RED, 1, cv2.LINE_AA)
    cv2.putText(img, f"{series.camera}: {what} per {check.window_s:g} s window", (MARGIN, 30),
                FONT, 0.55, BLACK, 1, cv2.LINE_AA)
    cv2.putText(img, _verdict(check, series), (MARGIN, MARGIN + HEIGHT + 40), FONT, 0.45,
                RED if any(series.flagged) else BLACK, 1, cv2.LINE_AA)
    return img


def _verdict(check: LogCheck, series: Series) -> str:
    """The panel's last line: not judged and why, drifted from when, or clean."""
    if series.unjudged:
        return f"not judged: {series.unjudged}"[:110]
    if not any(series.flagged):
        return "clean"
    first = series.flagged.index(True)
    value = series.values[series.metric][first]
    return (f"flagged from {check.span(first)[0]:g} s: {series.metric} {value:.3g} "
            f"(limit {series.limit:.3g})")


def _empty(check: LogCheck) -> np.ndarray:
    img = np.full((80, WIDTH + 2 * MARGIN, 3), 255, np.uint8)
    cv2.putText(img, "nothing to check", (MARGIN, 45), FONT, 0.6, BLACK, 1, cv2.LINE_AA)
    return img


def markdown(checks: list[LogCheck], figures: list[str]) -> str:
    """``report.md``: each log's verdict, its windows' limits, what was not checkable, its
    figure."""
    lines = ["# Calibration check", ""]
    for check, name in zip(checks, figures, strict=True):
        lines += [f"## {check.log}", "", check.summary(), ""]
        for series in check.series:
            flagged = sum(series.flagged)
            lines.append(f"- {series.camera} ({series.kind}): "
                         + (f"not judged: {series.unjudged}" if series.unjudged else
                            f"{series.metric} limit {series.limit:.4g}, {flagged} of "
                            f"{check.windows} windows flagged"))
        lines += [f"- {u.namespace}: not checkable: {u.reason}" for u in check.unchecked]
        lines += ["", f"![{name}]({name})", ""]
    return "\n".join(lines)


def figure_names(checks: list[LogCheck]) -> list[str]:
    """One PNG name per log, from its file name (numbered where two logs share one)."""
    return [f"{name.replace('.', '_')}_check.png" for name in entity_names(checks)]


def write_report(checks: list[LogCheck], folder: Path) -> list[Path]:
    """Write ``check.csv``, ``report.md``, the figures and ``check.rrd`` into ``folder``;
    their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    names = figure_names(checks)
    written = []
    for check, name in zip(checks, names, strict=True):
        _, png = cv2.imencode(".png", figure(check))
        write_bytes_atomic(folder / name, png.tobytes())
        written.append(folder / name)
    write_text_atomic(folder / "check.csv", csv_text(checks))
    write_text_atomic(folder / "report.md", markdown(checks, names) + "\n")
    write_recording(checks, folder / "check.rrd")
    return [folder / "check.csv", folder / "report.md", folder / "check.rrd", *written]
