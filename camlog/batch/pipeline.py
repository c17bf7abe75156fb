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

A step kind is a command's request and a runner (:mod:`.steps`); its keys are the
request's fields, checked as the command line checks them, minus what the batch sets itself
(input, output, ``overwrite``, progress). The ``process`` step's processor keys are
generated from :mod:`processors.registry`: a processor with a flag is ``NAME = true``, a
table of its options, or its primary option's value (``rectify = "ost.yaml"``); a flagless
one (throttle) gives its options as keys (``every = 3``). The keys of each step:

- resync: calibration, left, max_offset, offset, out_prefix, pattern, recover, right, size,
  slop, square
- calibrate: approximate, board_warp, calibration, camera, camera_name, check, diameter,
  dictionary, fix_aspect_ratio, fix_principal_point, k_coefficients, left, legacy_pattern,
  marker, max_chessboard_speed, model, pattern, recover, report, rig, right, size, square,
  tangent_dist, time_offset, zero_tangent_dist
- process: compress, drop_input, max_frames, output_ns, recover, topic; processor keys:
  edges, every, rate, rectify, red_pixels, resize, undistort
- throttle: recover, topic; processor keys: every, rate
- info: recover, verify
- check: calibration, camera, pattern, rate, size, square, threshold, window
- convert: compress, crf, decompress, end, format, profile, recover, start, topics
- export: end, every, format, jpeg_quality, recover, start, topic

Each step runs one of camlog's functions on an input log and may produce a log that later
steps read. :func:`run_step` is the only place that knows the step kinds.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from replay.bounded import read_text, toml_loads, yaml_load
from replay.storage import Location

from ..errors import PipelineError
from ..requests.fields import RequestError
from ..requests.table import keyed, request_from_table
from .steps import STEPS, StepKind, StepOutcome

__all__ = ["STEPS", "Pipeline", "Step", "StepKind", "StepOutcome", "load_pipeline",
           "parse_pipeline", "run_step"]


@dataclass(frozen=True)
class Step:
    """One step: what to ``run``, on which ``input``, with which options."""

    name: str
    run: str
    input: str
    options: dict[str, Any]
    request: Any = field(default=None, compare=False, repr=False)  # the options, validated


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


def run_step(step: Step, log: Location, out: Path, workers: int) -> StepOutcome:
    """Run one step on ``log`` (a path or a URI), writing under the local folder ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    kind = STEPS[step.run]
    request = dataclasses.replace(step.request, **kind.given(log, out))
    try:
        return kind.runner(request, out, workers)
    except RequestError as err:  # found with the log (its cameras, the board's spacing)
        raise PipelineError(f"{step.run}: {keyed(err)}") from None


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
        keys = STEPS[kind].keys
        bad = sorted(set(options) - keys)
        if bad:
            raise PipelineError(f"{where}: {kind} has no option {bad[0]!r} "
                                f"(options: {', '.join(sorted(keys)) or 'none'})")
        for key, value in options.items():
            _check_value(where, key, value)
        request: Any = request_from_table(STEPS[kind].request, options,
                                          step=f"{where}: {kind}")
        steps.append(Step(name, kind, source_step, options, request))
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
