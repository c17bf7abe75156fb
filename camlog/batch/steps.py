"""The step kinds of a pipeline: each is a command's request (whose fields are the step's
keys) and a runner that calls the command's flow with it.

The runner is given the request with its input log and output set (and ``overwrite`` on,
progress bars off), the step's table (for keys beyond the request's fields: the processors
of ``process`` and ``throttle``, generated from :mod:`processors.registry`), the step's
folder and the worker threads the batch gives it.
"""

from __future__ import annotations

import dataclasses
import textwrap
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from processors.errors import OptionValueError
from processors.registry import SPECS, spec_of
from processors.spec import Configured, ProcessorSpec
from replay.atomic import write_text_atomic

from ..errors import PipelineError
from ..processing.options import configure_values
from ..requests.calibrate import CalibrateRequest
from ..requests.check import CheckRequest
from ..requests.fields import batch_keys
from ..requests.logs import ConvertRequest, ExportRequest, InfoRequest
from ..requests.processing import ProcessRequest, ResyncRequest, ThrottleRequest

__all__ = ["STEPS", "StepKind", "StepOutcome", "keys_lines", "keys_table", "keys_worded",
           "step_processors"]


@dataclass
class StepOutcome:
    """What a step produced: a log later steps can read, key figures, files."""

    log: Path | None
    figures: dict[str, Any] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)


#: (request with its log and output set, the step's table, the step's folder, workers)
Runner = Callable[[Any, dict[str, Any], Path, int], StepOutcome]


@dataclass(frozen=True)
class StepKind:
    """A step kind: its request class, its runner, the name of its output under the step's
    folder ("": the folder) and the keys it takes beyond the request's fields."""

    request: type
    runner: Runner
    output: str = ""
    extra: frozenset[str] = frozenset()

    @property
    def keys(self) -> frozenset[str]:
        """Every key a step of this kind takes."""
        return batch_keys(self.request) | self.extra

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


# --- processors ---------------------------------------------------------------------------

def _processor_values(spec: ProcessorSpec, o: dict[str, Any]) -> dict[str, Any] | None:
    """The values a step gives one processor, or None when it does not choose it."""
    if not spec.flag:
        values = {opt.name: o.get(opt.name) for opt in spec.options}
        return values if any(v is not None for v in values.values()) else None
    value = o.get(spec.name)
    if value is None or value is False:
        return None
    if value is True:
        return {}
    if isinstance(value, dict):
        return dict(value)
    if spec.primary:
        return {spec.primary: value}
    raise PipelineError(f"{spec.name} must be true, false or a table of options")


@contextmanager
def keys_worded(step: str, specs: tuple[ProcessorSpec, ...]) -> Iterator[None]:
    """Reword :class:`OptionValueError` with the step's keys (``edges.low``, ``every``)."""
    try:
        yield
    except OptionValueError as err:
        spec = next((s for s in specs if s.name == err.processor), None)
        if spec is None:
            raise
        keys = [name if not spec.flag else spec.name if name == spec.primary
                else f"{spec.name}.{name}" for name in err.options]
        raise PipelineError(f"{step}: {', '.join(keys) or spec.name}: {err.problem}") from None


def step_processors(o: dict[str, Any], specs: tuple[ProcessorSpec, ...],
                    step: str = "process") -> list[Configured]:
    """The processors a step chooses, configured (errors name the step's keys)."""
    chosen = []
    with keys_worded(step, specs):
        for spec in specs:
            values = _processor_values(spec, o)
            if values is not None:
                chosen.append(configure_values(spec, values))
    return chosen


#: the keys of the processors: a flag each, and the options of the flagless ones
PROCESSOR_KEYS = frozenset({s.name for s in SPECS if s.flag}
                           | {o.name for s in SPECS if not s.flag for o in s.options})


# --- runners ------------------------------------------------------------------------------

def _files(path: Path) -> list[Path]:
    """A file, or the files of a folder."""
    return sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]


def _resync(request: ResyncRequest, o: dict[str, Any], out: Path,
            workers: int) -> StepOutcome:
    from ..processing.resync_log import resync_log

    result = resync_log(request)
    return StepOutcome(result.output, {"pairs": result.stats.pairs}, [result.output])


def _calibrate(request: CalibrateRequest, o: dict[str, Any], out: Path,
               workers: int) -> StepOutcome:
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


def _process(request: ProcessRequest, o: dict[str, Any], out: Path,
             workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    chosen = step_processors(o, SPECS)
    if not any(not c.spec.selects for c in chosen):
        raise PipelineError("process: enable at least one of "
                            f"{', '.join(s.name for s in SPECS if s.flag)}")
    with keys_worded("process", SPECS):
        result = process_log(dataclasses.replace(request, processors=tuple(chosen),
                                                 workers=workers))
    return StepOutcome(result.output, {"frames": result.frames_processed,
                                       "fps": round(result.fps, 1)}, [result.output])


def _throttle(request: ThrottleRequest, o: dict[str, Any], out: Path,
              workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    chosen = step_processors(o, (spec_of("throttle"),), "throttle")
    if not chosen:
        raise PipelineError("throttle: give every = N or rate = HZ")
    result = process_log(dataclasses.replace(request, processors=tuple(chosen)).processing())
    return StepOutcome(result.output, {"kept": result.frames_processed,
                                       "of": result.frames_read}, [result.output])


def _info(request: InfoRequest, o: dict[str, Any], out: Path, workers: int) -> StepOutcome:
    from camlog.logs.info import format_summary, summarize
    from replay.formats import open_reader

    with open_reader(request.log, recover=request.recover) as reader:
        text = format_summary(summarize(reader, verify=request.verify))
    path = out / "info.txt"
    write_text_atomic(path, text + "\n")
    return StepOutcome(None, {}, [path])


def _check(request: CheckRequest, o: dict[str, Any], out: Path, workers: int) -> StepOutcome:
    from ..check.flow import check_drift, options_of
    from ..check.report import write_report

    checked = check_drift(request.logs[0], options_of(request))
    flagged = [s for s in checked.series if any(s.flagged)]
    figures: dict[str, Any] = {
        "flagged_windows": int(sum(sum(s.flagged) for s in checked.series))}
    if flagged:
        figures["drifted_from_s"] = float(min(checked.span(s.flagged.index(True))[0]
                                              for s in flagged))
    return StepOutcome(None, figures, write_report([checked], request.output))


#: a converted log's name by its format (rosbag2: a folder)
CONVERTED = {"mcap": "converted.mcap", "ros1": "converted.bag", "rosbag2": "converted",
             "rosbag2-sqlite3": "converted"}


def _convert(request: ConvertRequest, o: dict[str, Any], out: Path,
             workers: int) -> StepOutcome:
    from camlog.logs.convert import convert_log

    output = out / CONVERTED[request.format or "mcap"]
    result = convert_log(dataclasses.replace(request, output=output))
    return StepOutcome(result.output, {"messages": result.messages,
                                       "reencoded": result.reencoded}, _files(result.output))


def _export(request: ExportRequest, o: dict[str, Any], out: Path,
            workers: int) -> StepOutcome:
    from ..processing.export_images import export_images

    result = export_images(request)
    return StepOutcome(None, {"frames": result.frames}, _files(result.output))


#: step kind -> its request and runner
STEPS: dict[str, StepKind] = {
    "resync": StepKind(ResyncRequest, _resync, "synced.mcap"),
    "calibrate": StepKind(CalibrateRequest, _calibrate),
    "process": StepKind(ProcessRequest, _process, "processed.mcap", PROCESSOR_KEYS),
    "throttle": StepKind(ThrottleRequest, _throttle, "throttled.mcap",
                         frozenset(o.name for o in spec_of("throttle").options)),
    "info": StepKind(InfoRequest, _info),
    "check": StepKind(CheckRequest, _check),
    "convert": StepKind(ConvertRequest, _convert),
    "export": StepKind(ExportRequest, _export, "images"),
}


def keys_table() -> list[str]:
    """The step kinds and their keys as Markdown table rows (``docs/batch.md`` and the
    pipeline module document them with these lines)."""
    rows = ["| step | keys (besides `run`, `name`, `input`) |", "|---|---|"]
    for name, kind in STEPS.items():
        own = ", ".join(f"`{k}`" for k in sorted(batch_keys(kind.request)))
        extra = ", ".join(f"`{k}`" for k in sorted(kind.extra))
        rows.append(f"| `{name}` | {own}{'; processor keys: ' + extra if extra else ''} |")
    return rows


def keys_lines(width: int = 92) -> list[str]:
    """The step kinds and their keys as wrapped plain text, a paragraph per step (the
    pipeline module's docstring holds these lines)."""
    lines = []
    for name, kind in STEPS.items():
        keys = ", ".join(sorted(batch_keys(kind.request)))
        extra = f"; processor keys: {', '.join(sorted(kind.extra))}" if kind.extra else ""
        lines += textwrap.wrap(f"- {name}: {keys}{extra}", width, subsequent_indent="  ")
    return lines
