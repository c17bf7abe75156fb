"""What ``camlog check`` writes: ``check.csv`` (one row per log, camera, window and
metric), ``report.md`` and one PNG per log of its flagged metrics over time."""

from __future__ import annotations

import csv
import io
import itertools
import math
from pathlib import Path

import cv2
import numpy as np

from camlog.calibrate.figures import BLACK, BLUE, FONT, GREY, RED
from replay.atomic import write_bytes_atomic, write_text_atomic

from .flow import LogCheck, Series

__all__ = ["CSV_COLUMNS", "figure", "write_report"]

CSV_COLUMNS = ("log", "camera", "start_s", "end_s", "metric", "value", "flagged")
WIDTH, HEIGHT, MARGIN = 720, 180, 60
SHADE = (215, 215, 250)


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
    """Each check's flagged metric per window over time (BGR ``(H, W, 3)`` uint8): the
    values, the limit (dashed red) and the flagged windows (shaded)."""
    panels = [_panel(check, s) for s in check.series] or [_empty(check)]
    return np.vstack(panels)


def _y(value: float, top: float) -> int:
    return int(MARGIN + HEIGHT - min(value, top) / top * HEIGHT)


def _panel(check: LogCheck, series: Series) -> np.ndarray:
    img = np.full((HEIGHT + 2 * MARGIN, WIDTH + 2 * MARGIN, 3), 255, np.uint8)
    values = series.values[series.metric]
    finite = [v for v in values if math.isfinite(v)]
    limited = math.isfinite(series.limit)
    top = max([*finite, series.limit if limited else 0.0, 1e-9]) * 1.2
    span_s = check.windows * check.window_s

    def x(t_s: float) -> int:
        return int(MARGIN + t_s / span_s * WIDTH)

    for index, flagged in enumerate(series.flagged):
        if flagged:
            start, end = check.span(index)
            cv2.rectangle(img, (x(start), MARGIN), (x(end), MARGIN + HEIGHT), SHADE, -1)
    for dash in range(MARGIN, MARGIN + WIDTH, 12) if limited else ():
        cv2.line(img, (dash, _y(series.limit, top)), (min(dash + 6, MARGIN + WIDTH),
                                                      _y(series.limit, top)), RED, 1)
    points = [(x(sum(check.span(i)) / 2), _y(v, top)) for i, v in enumerate(values)
              if math.isfinite(v)]
    for a, b in itertools.pairwise(points):
        cv2.line(img, a, b, BLUE, 2, cv2.LINE_AA)
    for p in points:
        cv2.circle(img, p, 3, BLUE, -1, cv2.LINE_AA)
    cv2.rectangle(img, (MARGIN, MARGIN), (MARGIN + WIDTH, MARGIN + HEIGHT), BLACK, 1)
    for t in range(int(span_s) + 1):
        if t % max(1, int(span_s) // 10) == 0:
            cv2.putText(img, f"{t}", (x(t) - 4, MARGIN + HEIGHT + 16), FONT, 0.4, BLACK, 1,
                        cv2.LINE_AA)
    cv2.putText(img, "s", (MARGIN + WIDTH + 8, MARGIN + HEIGHT + 16), FONT, 0.4, BLACK, 1)
    cv2.putText(img, f"{top:.3g}", (4, MARGIN + 4), FONT, 0.4, GREY, 1, cv2.LINE_AA)
    if limited:
        cv2.putText(img, f"limit {series.limit:.3g}",
                    (MARGIN + WIDTH - 110, _y(series.limit, top) - 6), FONT, 0.4, RED, 1,
                    cv2.LINE_AA)
    title = f"{series.camera}: {series.metric} per {check.window_s:g} s window"
    cv2.putText(img, title, (MARGIN, 30), FONT, 0.55, BLACK, 1, cv2.LINE_AA)
    return img


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
            lines.append(f"- {series.camera} ({series.kind}): {series.metric} limit "
                         f"{series.limit:.4g}, {flagged} of {check.windows} windows flagged")
        lines += [f"- {u.namespace}: not checkable: {u.reason}" for u in check.unchecked]
        lines += ["", f"![{name}]({name})", ""]
    return "\n".join(lines)


def figure_names(checks: list[LogCheck]) -> list[str]:
    """One PNG name per log, from its file name (numbered where two logs share one)."""
    names: list[str] = []
    for check in checks:
        stem = Path(check.log.rstrip("/")).name.replace(".", "_") or "log"
        name, count = f"{stem}_check.png", 1
        while name in names:
            count += 1
            name = f"{stem}_{count}_check.png"
        names.append(name)
    return names


def write_report(checks: list[LogCheck], folder: Path) -> list[Path]:
    """Write ``check.csv``, ``report.md`` and the figures into ``folder``; their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    names = figure_names(checks)
    written = []
    for check, name in zip(checks, names, strict=True):
        _, png = cv2.imencode(".png", figure(check))
        write_bytes_atomic(folder / name, png.tobytes())
        written.append(folder / name)
    write_text_atomic(folder / "check.csv", csv_text(checks))
    write_text_atomic(folder / "report.md", markdown(checks, names) + "\n")
    return [folder / "check.csv", folder / "report.md", *written]
