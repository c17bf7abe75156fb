"""``check.rrd``: the check as a rerun recording, every log under an entity of its own.

Per log ``/<log>`` (its file name, numbered where two logs share one) and checked camera
``/<log>/<camera namespace>``: each metric as a scalar series at its windows' centres
(``…/<metric>``), the limit its flagged metric is compared with (``…/limit``, over the
log's span) and the flagged windows as a step series (``…/flagged``: 1 over a flagged
window, 0 elsewhere); the log's verdict as a text entry (``/<log>/verdict``). Times are
seconds from the log's start on the ``time_from_start`` timeline. The default layout shows
one tab per log: the flagged metric with its limit, the fitted rotation, the flags.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from .flow import LogCheck, Series

__all__ = ["TIMELINE", "entity_names", "write_recording"]

TIMELINE = "time_from_start"
METRIC_RGB, LIMIT_RGB, FLAGGED_RGB = (40, 90, 200), (220, 40, 40), (240, 150, 40)
#: a pair's rotation, shown together in the second plot
ROTATION = ("pitch_deg", "roll_deg")


def entity_names(checks: list[LogCheck]) -> list[str]:
    """One entity name per log: its file name, numbered where two logs share one."""
    names: list[str] = []
    for check in checks:
        stem = Path(check.log.rstrip("/")).name or "log"
        name, count = stem, 1
        while name in names:
            count += 1
            name = f"{stem}_{count}"
        names.append(name)
    return names


def write_recording(checks: list[LogCheck], path: Path) -> Path:
    """Write every log's check into one ``.rrd`` at ``path`` (replacing it)."""
    import rerun as rr

    from rerun_export import RecordingSink

    roots = [f"/{rr.escape_entity_path_part(n)}" for n in entity_names(checks)]
    with RecordingSink(output=path, overwrite=True, blueprint=_blueprint(checks, roots),
                       application_id="camlog_check") as sink:
        for check, root in zip(checks, roots, strict=True):
            sink.rec.set_time(TIMELINE, duration=0.0)
            sink.rec.log(f"{root}/verdict", rr.TextLog(check.summary(), level=_level(check)))
            for series in check.series:
                _log_series(sink.rec, check, series, f"{root}{series.camera}")
    return path


def _level(check: LogCheck) -> str:
    return {"clean": "INFO", "drifted": "WARN"}.get(check.verdict, "DEBUG")


def _log_series(rec: Any, check: LogCheck, series: Series, origin: str) -> None:
    import rerun as rr

    for metric in series.values:
        colours = [METRIC_RGB] if metric == series.metric else None
        rec.log(f"{origin}/{metric}", rr.SeriesLines(names=metric, colors=colours),
                static=True)
    rec.log(f"{origin}/limit", rr.SeriesLines(names="limit", colors=[LIMIT_RGB]), static=True)
    rec.log(f"{origin}/flagged", rr.SeriesLines(names="flagged", colors=[FLAGGED_RGB]),
            static=True)
    for index in range(check.windows):
        start, end = check.span(index)
        rec.set_time(TIMELINE, duration=(start + end) / 2)
        for metric, values in series.values.items():
            if math.isfinite(values[index]):
                rec.log(f"{origin}/{metric}", rr.Scalars(values[index]))
        flag = float(series.flagged[index])
        for t_s in (start, end):  # a step: flat over the window
            rec.set_time(TIMELINE, duration=t_s)
            rec.log(f"{origin}/flagged", rr.Scalars(flag))
    if math.isfinite(series.limit):
        for t_s in (0.0, check.windows * check.window_s):
            rec.set_time(TIMELINE, duration=t_s)
            rec.log(f"{origin}/limit", rr.Scalars(series.limit))


def _blueprint(checks: list[LogCheck], roots: list[str]) -> Any:
    import rerun.blueprint as rrb

    tabs = []
    for check, root in zip(checks, roots, strict=True):
        plots: list[Any] = []
        for series in check.series:
            origin = f"{root}{series.camera}"
            plots.append(rrb.TimeSeriesView(
                origin=origin, contents=[f"$origin/{series.metric}", "$origin/limit"],
                name=f"{series.camera}: {series.metric}"))
            rotation = [f"$origin/{m}" for m in ROTATION if m in series.values]
            if rotation:
                plots.append(rrb.TimeSeriesView(origin=origin, contents=rotation,
                                                name=f"{series.camera}: rotation (deg)"))
            plots.append(rrb.TimeSeriesView(origin=origin, contents="$origin/flagged",
                                            name=f"{series.camera}: flagged"))
        plots.append(rrb.TextLogView(origin=f"{root}/verdict", name="verdict"))
        tabs.append(rrb.Vertical(*plots, name=Path(check.log.rstrip("/")).name or "log"))
    return rrb.Blueprint(rrb.Tabs(*tabs), collapse_panels=True)
