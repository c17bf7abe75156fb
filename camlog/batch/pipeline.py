"""Pipelines: a small TOML/YAML file naming steps (resync, calibrate, process, …) and options.

```toml
[[steps]]
run = "resync"                       # left/right/slop/out_prefix as for camlog resync

[[steps]]
run = "calibrate"                    # input: the previous step's log (here, the resync output)
size = "7x6"
square = 0.01
left = "/stereo_sync/left"
right = "/stereo_sync/right"

[[steps]]
run = "process"
input = "log"                        # "log" (the batch input), "previous", or a step name
topic = "/unsynced/left/image_raw"
red_pixels = true
edges = {low = 50, high = 150}

[[steps]]
run = "check"                        # camlog check: window/rate/threshold/calibration/...
input = "log"
window = 2.0
```

The ``process`` step's keys are generated from :mod:`processors.registry`: a processor with
a flag is ``NAME = true``, a table of its options, or its primary option's value
(``rectify = "ost.yaml"``); a flagless one (throttle) gives its options as keys
(``every = 3``).

Each step runs one of camlog's functions on an input log and may produce a log that later
steps read. :func:`run_step` is the only place that knows the step kinds.
"""

from __future__ import annotations

import hashlib
import json
import math
import tomllib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from processors.errors import OptionValueError
from processors.registry import SPECS, spec_of
from processors.spec import Configured, ProcessorSpec
from replay.atomic import write_text_atomic
from replay.bounded import read_text, toml_loads, yaml_load
from replay.storage import Location
from replay.topics import RESYNC_PREFIX

from ..errors import PipelineError
from ..processing.options import configure_values


@dataclass(frozen=True)
class Step:
    """One step: what to ``run``, on which ``input``, with which options."""

    name: str
    run: str
    input: str
    options: dict[str, Any]


@dataclass
class StepOutcome:
    """What a step produced: a log later steps can read, key figures, files."""

    log: Path | None
    figures: dict[str, Any] = field(default_factory=dict)
    files: list[Path] = field(default_factory=list)


@dataclass(frozen=True)
class Pipeline:
    """A validated pipeline: its steps and where it was read from."""
    steps: tuple[Step, ...]
    source: str

    def digest(self) -> str:
        """Hash of everything that shapes the outputs (for up-to-date checks)."""
        from replay._version import VERSION

        text = json.dumps([[s.name, s.run, s.input, s.options] for s in self.steps],
                          sort_keys=True, default=str)
        return hashlib.sha256(f"{VERSION}\n{text}".encode()).hexdigest()[:16]


# --- step kinds --------------------------------------------------------------------------

def _topics(o: dict[str, Any], step: str) -> list[str]:
    topics = o.get("topic")
    if isinstance(topics, str):
        return [topics]
    if isinstance(topics, list) and topics and all(isinstance(t, str) for t in topics):
        return topics
    raise PipelineError(f"{step}: give topic = the image topic (or a list of topics) to process")


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


def _resync(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from ..processing.resync_log import resync_log

    result = resync_log(log, out / "synced.mcap", left=o.get("left", "/unsynced/left"),
                        right=o.get("right", "/unsynced/right"),
                        out_prefix=o.get("out_prefix", RESYNC_PREFIX), slop_s=o.get("slop"),
                        overwrite=True)
    stats = result.stats
    return StepOutcome(result.output, {"pairs": stats.pairs}, [result.output])


def _calibrate(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from processors.calibration.board import make_board
    from processors.calibration.options import CalibrationOptions, tangential_mode

    from ..calibrate.flow import calibrate_log

    if "left" in o or "right" in o:
        cameras = [o.get("left", ""), o.get("right", "")]
    elif "camera" in o:
        cameras = [o["camera"]]
    else:
        raise PipelineError("calibrate: give camera = NS, or left and right")
    run = calibrate_log(
        log, board=make_board(str(o.get("size", "")), float(o.get("square", 0))),
        cameras=cameras, output_dir=out,
        options=CalibrationOptions(
            fix_principal_point=bool(o.get("fix_principal_point", False)),
            fix_aspect_ratio=bool(o.get("fix_aspect_ratio", False)),
            tangential=tangential_mode(bool(o.get("zero_tangent_dist", False)),
                                       bool(o.get("tangent_dist", False))),
            k_coefficients=int(o.get("k_coefficients", 2))),
        approximate_s=o.get("approximate"), camera_name=o.get("camera_name"),
        overwrite=True, workers=workers,
        progress=False)
    summary = run.summary
    figures: dict[str, Any] = {}
    for camera in summary.cameras:
        key = camera.namespace.strip("/").split("/")[-1]
        figures[f"{key}_rms_px"] = round(camera.rms_px, 4)
        figures[f"{key}_fx"] = round(camera.parameters["fx"].value, 3)
    if summary.stereo is not None:
        figures["baseline_m"] = round(summary.stereo.baseline_m, 6)
        figures["epipolar_px"] = round(summary.stereo.epipolar_rms_px, 4)
    return StepOutcome(out / "calibration.mcap", figures, run.files)


def _process(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    topics = _topics(o, "process")
    chosen = step_processors(o, SPECS)
    if not any(not c.spec.selects for c in chosen):
        raise PipelineError("process: enable at least one of "
                          f"{', '.join(s.name for s in SPECS if s.flag)}")
    with keys_worded("process", SPECS):
        result = process_log(log, out / "processed.mcap", topics=topics, processors=chosen,
                             output_ns=o.get("output_ns"), compress=o.get("compress"),
                             drop_input=bool(o.get("drop_input", False)), overwrite=True,
                             workers=workers)
    return StepOutcome(result.output, {"frames": result.frames_processed,
                                       "fps": round(result.fps, 1)}, [result.output])


def _throttle(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from ..processing.process_log import process_log

    topics = _topics(o, "throttle")
    chosen = step_processors(o, (spec_of("throttle"),), "throttle")
    if not chosen:
        raise PipelineError("throttle: give every = N or rate = HZ")
    result = process_log(log, out / "throttled.mcap", topics=topics, processors=chosen,
                         thin=True, overwrite=True)
    return StepOutcome(result.output, {"kept": result.frames_processed,
                                       "of": result.frames_read}, [result.output])


def _info(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from camlog.logs.info import format_summary, summarize
    from replay.formats import open_reader

    with open_reader(log) as reader:
        text = format_summary(summarize(reader))
    out.mkdir(parents=True, exist_ok=True)
    path = out / "info.txt"
    write_text_atomic(path, text + "\n")
    return StepOutcome(None, {}, [path])


def _check(log: Location, out: Path, o: dict[str, Any], workers: int) -> StepOutcome:
    from processors.calibration.board import make_board

    from ..check.flow import CheckOptions, check_log
    from ..check.report import write_report

    if ("size" in o) != ("square" in o):
        raise PipelineError("check: a board needs both size and square")
    cameras = o.get("camera", [])
    options = CheckOptions(
        window_s=float(o.get("window", 2.0)), rate_hz=float(o.get("rate", 5.0)),
        board=make_board(str(o["size"]), float(o["square"]), str(o.get("pattern", "chessboard")))
        if "size" in o else None,
        calibration=Path(o["calibration"]) if "calibration" in o else None,
        cameras=[cameras] if isinstance(cameras, str) else list(cameras),
        threshold=float(o["threshold"]) if "threshold" in o else None)
    if not (options.window_s > 0 and options.rate_hz > 0):
        raise PipelineError("check: window and rate must be > 0")
    checked = check_log(log, options)
    flagged = [s for s in checked.series if any(s.flagged)]
    figures: dict[str, Any] = {
        "flagged_windows": int(sum(sum(s.flagged) for s in checked.series))}
    if flagged:
        figures["drifted_from_s"] = float(min(checked.span(s.flagged.index(True))[0]
                                              for s in flagged))
    return StepOutcome(None, figures, write_report([checked], out))


Runner = Callable[[Location, Path, dict[str, Any], int], StepOutcome]

#: step kind -> (allowed option keys, runner)
STEPS: dict[str, tuple[frozenset[str], Runner]] = {
    "resync": (frozenset({"left", "right", "slop", "out_prefix"}), _resync),
    "calibrate": (frozenset({"size", "square", "camera", "left", "right", "approximate",
                             "fix_principal_point", "fix_aspect_ratio", "zero_tangent_dist",
                             "tangent_dist", "k_coefficients", "camera_name"}),
                  _calibrate),
    "process": (frozenset({"topic", "output_ns", "compress", "drop_input"}
                          | {s.name for s in SPECS if s.flag}
                          | {o.name for s in SPECS if not s.flag for o in s.options}), _process),
    "throttle": (frozenset({"topic", *(o.name for o in spec_of("throttle").options)}),
                 _throttle),
    "info": (frozenset(), _info),
    "check": (frozenset({"window", "rate", "threshold", "calibration", "camera", "size",
                         "square", "pattern"}), _check),
}


def run_step(step: Step, log: Location, out: Path, workers: int) -> StepOutcome:
    """Run one step on ``log`` (a path or a URI), writing under the local folder ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    return STEPS[step.run][1](log, out, step.options, workers)


# --- loading -----------------------------------------------------------------------------

def _scalar(value: Any) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    return isinstance(value, str | bool | int)


def _check_value(where: str, key: str, value: Any, *, text: bool = False) -> None:
    """A pipeline value is a scalar, a list of scalars (topics) or a table of scalars (a
    processor's options), with finite numbers: deeper nesting, NaN and infinities are
    refused here in one line rather than failing inside a step."""
    if text:
        ok, kind = isinstance(value, str) and bool(value.strip()), "a non-empty text"
    else:
        ok = _scalar(value) or (isinstance(value, list) and all(map(_scalar, value))) or (
            isinstance(value, dict) and all(isinstance(k, str) and _scalar(v)
                                            for k, v in value.items()))
        kind = "a value, a list of values or a table of values (finite numbers, no nesting)"
    if not ok:
        shown = repr(value)
        raise PipelineError(f"{where}: {key} must be {kind}, got "
                            f"{shown if len(shown) <= 60 else shown[:57] + '...'}")


def parse_pipeline(raw: Any, source: str) -> Pipeline:
    """Validate raw pipeline data (from TOML or YAML)."""
    if not isinstance(raw, dict) or not isinstance(raw.get("steps"), list) or not raw["steps"]:
        raise PipelineError(f"{source}: a pipeline needs a non-empty list of [[steps]]")
    unknown_top = set(raw) - {"steps", "description"}
    if unknown_top:
        raise PipelineError(f"{source}: unknown key {sorted(unknown_top)[0]!r}")
    steps: list[Step] = []
    for index, table in enumerate(raw["steps"]):
        where = f"{source}: steps[{index}]"
        if not isinstance(table, dict) or "run" not in table:
            raise PipelineError(f"{where}: each step needs run = one of {', '.join(STEPS)}")
        kind = table["run"]
        if not isinstance(kind, str) or kind not in STEPS:
            raise PipelineError(f"{where}: unknown step {kind!r} (known: {', '.join(STEPS)})")
        for key in ("name", "input"):
            if key in table:
                _check_value(where, key, table[key], text=True)
        name = str(table.get("name", kind))
        if any(s.name == name for s in steps):
            raise PipelineError(f"{where}: step name {name!r} is used twice; give name = ...")
        source_step = str(table.get("input", "previous"))
        known = {"log", "previous", *(s.name for s in steps)}
        if source_step not in known:
            raise PipelineError(f"{where}: input {source_step!r} is not 'log', 'previous' or an "
                              "earlier step's name")
        options = {k: v for k, v in table.items() if k not in ("run", "name", "input")}
        bad = sorted(set(options) - STEPS[kind][0])
        if bad:
            raise PipelineError(f"{where}: {kind} has no option {bad[0]!r} "
                              f"(options: {', '.join(sorted(STEPS[kind][0])) or 'none'})")
        for key, value in options.items():
            _check_value(where, key, value)
        steps.append(Step(name, kind, source_step, options))
    return Pipeline(tuple(steps), source)


def load_pipeline(path: Path) -> Pipeline:
    """Read a pipeline from a .toml, .yaml or .yml file."""
    text = read_text(path, PipelineError, what="pipeline file")
    name = f"pipeline file {path}"
    if path.suffix in (".yaml", ".yml"):
        from ruamel.yaml.error import YAMLError

        try:
            raw = yaml_load(text, name, PipelineError)
        except YAMLError as err:
            raise PipelineError(f"{path}: not valid YAML: {str(err).splitlines()[0]}") from None
    else:
        try:
            raw = toml_loads(text, name, PipelineError)
        except tomllib.TOMLDecodeError as err:
            raise PipelineError(f"{path}: not valid TOML: {err}") from None
    return parse_pipeline(raw, str(path))
