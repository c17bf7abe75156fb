"""The step kinds of a pipeline: each is a command's request (whose fields are the step's
keys) and a runner that calls the command's flow with it.

The runner is given the request with its input log and output set (and ``overwrite`` on,
progress bars off), the step's folder and the worker threads the batch gives it. The
processors of ``process`` and ``throttle`` are fields of their requests (generated from
:mod:`processors.registry`), keys like any other.
"""

from __future__ import annotations

import dataclasses
import textwrap
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from replay.atomic import write_text_atomic

from ..requests.calibrate import CalibrateRequest
from ..requests.check import CheckRequest
from ..requests.fields import arg_of, batch_keys, key_of, request_fields
from ..requests.logs import ConvertRequest, ExportRequest, InfoRequest
from ..requests.processing import ProcessRequest, ResyncRequest, ThrottleRequest

__all__ = ["STEPS", "StepKind", "StepOutcome", "keys_lines", "keys_table"]


@dataclass
class StepOutcome:
    """What a step produced: a log later steps can read, key figures, files."""

    log: Path | None
    figures: dict[str, Any] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)


#: (request with its log and output set, the step's folder, workers)
Runner = Callable[[Any, Path, int], StepOutcome]


@dataclass(frozen=True)
class StepKind:
    """A step kind: its request class (whose fields are its keys), its runner and the name
    of its output under the step's folder ("": the folder)."""

    request: type
    runner: Runner
    output: str = ""

    @property
    def keys(self) -> frozenset[str]:
        """Every key a step of this kind takes."""
        return batch_keys(self.request)

    def given(self, log: Any, out: Path) -> dict[str, Any]:
        """What the batch sets in the request: input, output, overwrite, progress."""
        names = {f.name for f in dataclasses.fields(self.request)}
        inputs = {"log": log, "input": log, "logs": (log,)}
        given: dict[str, Any] = {k: v for k, v in inputs.items() if k in names}
        if "output" in names:
            given["output"] = out / self.output if self.output else out
        if "overwrite" in names:
            given["overwrite"] = True
        if "progress" in names:
            given["progress"] = False
        return given


# --- runners ------------------------------------------------------------------------------

def _files(path: Path) -> list[Path]:
    """A file, or the files of a folder."""
    return sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]


def _resync(request: ResyncRequest, out: Path, workers: int) -> StepOutcome:
    from ..processing.resync_log import resync_log

    result = resync_log(request)
    return StepOutcome(result.output, {"pairs": result.stats.pairs}, [result.output])


def _calibrate(request: CalibrateRequest, out: Path, workers: int) -> StepOutcome:
    if request.check:
        from ..calibrate.check import measure_calibration

        checked = measure_calibration(request)
        path = out / "check.txt"
        write_text_atomic(path, "\n".join(checked.lines()) + "\n")
        return StepOutcome(None, {"views": checked.views}, [path])
    from ..calibrate.flow import calibrate_log

    run = calibrate_log(request, workers=workers)
    summary = run.summary
    figures: dict[str, Any] = {}
    for camera in summary.cameras:
        key = camera.namespace.strip("/").split("/")[-1]
        figures[f"{key}_rms_px"] = round(camera.rms_px, 4)
        figures[f"{key}_fx"] = round(camera.parameters["fx"].value, 3)
    if summary.stereo is not None:
        figures["baseline_m"] = round(summary.stereo.baseline_m, 6)
        figures["epipolar_px"] = round(summary.stereo.epipolar_rms_px, 4)
    return StepOutcome(out / "calibration.mcap" if request.report else None, figures,
                       run.files)


def _process(request: ProcessRequest, out: Path, workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    result = process_log(dataclasses.replace(request, workers=workers))
    return StepOutcome(result.output, {"frames": result.frames_processed,
                                       "fps": round(result.fps, 1)}, [result.output])


def _throttle(request: ThrottleRequest, out: Path, workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    result = process_log(request.processing())
    return StepOutcome(result.output, {"kept": result.frames_processed,
                                       "of": result.frames_read}, [result.output])


def _info(request: InfoRequest, out: Path, workers: int) -> StepOutcome:
    from camlog.logs.info import format_summary, summarize
    from replay.formats import open_reader

    with open_reader(request.log, recover=request.recover) as reader:
        text = format_summary(summarize(reader, verify=request.verify))
    path = out / "info.txt"
    write_text_atomic(path, text + "\n")
    return StepOutcome(None, {}, [path])


def _check(request: CheckRequest, out: Path, workers: int) -> StepOutcome:
    from ..check.run import check_logs

    done = check_logs(request)
    checked = done.checks[0]
    flagged = [s for s in checked.series if any(s.flagged)]
    figures: dict[str, Any] = {
        "flagged_windows": int(sum(sum(s.flagged) for s in checked.series))}
    if flagged:
        figures["drifted_from_s"] = float(min(checked.span(s.flagged.index(True))[0]
                                              for s in flagged))
    return StepOutcome(None, figures, done.files)


#: a converted log's name by its format (rosbag2: a folder)
CONVERTED = {"mcap": "converted.mcap", "ros1": "converted.bag", "rosbag2": "converted",
             "rosbag2-sqlite3": "converted"}


def _convert(request: ConvertRequest, out: Path, workers: int) -> StepOutcome:
    from camlog.logs.convert import convert_log

    output = out / CONVERTED[request.format or "mcap"]
    result = convert_log(dataclasses.replace(request, output=output))
    return StepOutcome(result.output, {"messages": result.messages,
                                       "reencoded": result.reencoded}, _files(result.output))


def _export(request: ExportRequest, out: Path, workers: int) -> StepOutcome:
    from ..processing.export_images import export_images

    result = export_images(request)
    return StepOutcome(None, {"frames": result.frames}, _files(result.output))


#: step kind -> its request and runner
STEPS: dict[str, StepKind] = {
    "resync": StepKind(ResyncRequest, _resync, "synced.mcap"),
    "calibrate": StepKind(CalibrateRequest, _calibrate),
    "process": StepKind(ProcessRequest, _process, "processed.mcap"),
    "throttle": StepKind(ThrottleRequest, _throttle, "throttled.mcap"),
    "info": StepKind(InfoRequest, _info),
    "check": StepKind(CheckRequest, _check),
    "convert": StepKind(ConvertRequest, _convert),
    "export": StepKind(ExportRequest, _export, "images"),
}


def _keys(kind: StepKind) -> tuple[list[str], list[str]]:
    """A step kind's own keys and its processors' keys (those listed under a processor's
    heading), each sorted."""
    fields = [f for f in request_fields(kind.request) if key_of(f) in kind.keys]
    return (sorted(key_of(f) for f in fields if not arg_of(f).group),
            sorted(key_of(f) for f in fields if arg_of(f).group))


def keys_table() -> list[str]:
    """The step kinds and their keys as Markdown table rows (``docs/batch.md`` and the
    pipeline module document them with these lines)."""
    rows = ["| step | keys (besides `run`, `name`, `input`) |", "|---|---|"]
    for name, kind in STEPS.items():
        own, processors = _keys(kind)
        extra = ", ".join(f"`{k}`" for k in processors)
        rows.append(f"| `{name}` | {', '.join(f'`{k}`' for k in own)}"
                    f"{'; processor keys: ' + extra if extra else ''} |")
    return rows


def keys_lines(width: int = 92) -> list[str]:
    """The step kinds and their keys as wrapped plain text, a paragraph per step (the
    pipeline module's docstring holds these lines)."""
    lines = []
    for name, kind in STEPS.items():
        own, processors = _keys(kind)
        extra = f"; processor keys: {', '.join(processors)}" if processors else ""
        lines += textwrap.wrap(f"- {name}: {', '.join(own)}{extra}", width,
                               subsequent_indent="  ")
    return lines
