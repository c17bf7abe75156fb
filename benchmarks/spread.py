"""How far from the truth several tools land over many seeds: the median and the 80th
percentile of each figure's |error|, one row per case and figure, one column per tool."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .calibration_truth import Accuracy

#: "OpenCV script": a user's whole script on the log, its own detection and pairing (a stereo
#: pair of free-running cameras: :mod:`benchmarks.opencv_stereo_log`)
TOOLS = ["camlog", "camlog default", "OpenCV", "OpenCV script", "mrcal"]
#: case -> tool -> one accuracy per seed
Results = dict[str, dict[str, list[Accuracy]]]
#: figure name -> its value in an accuracy (None: not measured, e.g. a mono camera's baseline)
FIGURES: dict[str, Callable[[Accuracy], float | None]] = {
    "fx %": lambda a: a.fx_percent,
    "fy %": lambda a: a.fy_percent,
    "principal point px": lambda a: a.principal_px,
    "max projection px": lambda a: max(a.max_difference_px),
    "rotation °": lambda a: a.rotation_deg,
    "baseline %": lambda a: a.baseline_percent,
}
PERCENTILE = 80


def spread(values: list[float]) -> tuple[float, float]:
    """Median and :data:`PERCENTILE` th percentile of ``|values|`` (non-empty)."""
    magnitudes = np.abs(np.asarray(values, dtype=np.float64))
    return float(np.median(magnitudes)), float(np.percentile(magnitudes, PERCENTILE))


def cell(values: list[float]) -> str:
    """``median / p80`` (4 significant digits), or ``-`` with no values."""
    if not values:
        return "-"
    median, high = spread(values)
    return f"{median:.4g} / {high:.4g}"


def _count(done: int, failed: int) -> str:
    """How many seeds a tool calibrated (and failed on); ``-``: it did not take part."""
    if not done and not failed:
        return "-"
    return f"n {done}" + (f", {failed} failed" if failed else "")


def table(results: Results, tools: list[str],
          failed: dict[tuple[str, str], int] | None = None) -> list[str]:
    """The lines of the table: a header, then per case its seed counts (``n``, with
    failures) and a row per figure it measured."""
    failed = failed or {}
    width = 22
    lines = [f"|error| against the truth over the seeds: median / {PERCENTILE}th percentile",
             f"{'case':14} {'figure':20}" + "".join(f" {t:>{width}}" for t in tools)]
    for case, by_tool in results.items():
        counts = [_count(len(by_tool.get(t, [])), failed.get((case, t), 0)) for t in tools]
        lines.append(f"{case:14} {'seeds':20}" + "".join(f" {c:>{width}}" for c in counts))
        for figure, value in FIGURES.items():
            columns = [[v for a in by_tool.get(t, []) if (v := value(a)) is not None]
                       for t in tools]
            if any(columns):
                lines.append(f"{'':14} {figure:20}"
                             + "".join(f" {cell(c):>{width}}" for c in columns))
    return lines


def markdown_rows(results: Results, tools: list[str], labels: dict[str, str],
                  failed: dict[tuple[str, str], int] | None = None) -> dict[str, list[list[str]]]:
    """Per case, the rows of the docs' table: its label (``labels``), then a row per figure
    it measured (first cell empty) with ``median / p80`` per tool; the seeds each tool
    calibrated (and failed on) end the case."""
    failed = failed or {}
    found: dict[str, list[list[str]]] = {}
    for case, by_tool in results.items():
        rows = []
        for figure, value in FIGURES.items():
            columns = [[v for a in by_tool.get(t, []) if (v := value(a)) is not None]
                       for t in tools]
            if any(columns):
                rows.append(["", figure, *("" if not c else cell(c) for c in columns)])
        rows.append(["", "seeds", *(_count(len(by_tool.get(t, [])), failed.get((case, t), 0))
                                    for t in tools)])
        rows[0][0] = labels.get(case, case)
        found[case] = rows
    return found
