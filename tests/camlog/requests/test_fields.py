"""Every option of every request reaches the three places that take it: the command line, a
batch pipeline step and a golden job; an option a place does not take is listed here with
the reason."""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import Field
from typing import Any

import pytest

from camlog.batch.pipeline import STEPS, parse_pipeline
from camlog.cli import build_parser
from camlog.golden.jobs import Calibrate, Process, Resync
from camlog.requests.calibrate import CalibrateRequest
from camlog.requests.check import CheckRequest
from camlog.requests.fields import Arg, arg_of, request_fields
from camlog.requests.logs import ConvertRequest, ExportRequest, ImportRequest, InfoRequest
from camlog.requests.play import PlayRequest, ViewRequest
from camlog.requests.processing import ProcessRequest, ResyncRequest, ThrottleRequest
from camlog.requests.table import table_value
from camlog.requests.values import namespaces

#: command -> (its request, the smallest command line it accepts)
COMMANDS: dict[str, tuple[type, list[str]]] = {
    "calibrate": (CalibrateRequest, ["in.mcap", "-s", "7x6", "-q", "0.01"]),
    "resync": (ResyncRequest, ["in.mcap", "-o", "out.mcap"]),
    "process": (ProcessRequest, ["in.mcap", "-o", "out.mcap", "--topic", "/c/image_raw",
                                 "--edges"]),
    "throttle": (ThrottleRequest, ["in.mcap", "-o", "out.mcap", "--topic", "/c/image_raw",
                                   "--every", "2"]),
    "convert": (ConvertRequest, ["in.mcap", "out.mcap"]),
    "export": (ExportRequest, ["in.mcap", "--topic", "/c/image_raw", "-o", "frames"]),
    "info": (InfoRequest, ["in.mcap"]),
    "check": (CheckRequest, ["in.mcap"]),
    "play": (PlayRequest, ["in.mcap"]),
    "view": (ViewRequest, ["in.mcap"]),
    "import": (ImportRequest, ["frames", "-o", "out.mcap"]),
}

#: the fields a batch step does not take as keys, and why
SET_BY_THE_BATCH = {
    "log": "the step's input: the batch's log or an earlier step's output",
    "input": "the step's input: the batch's log or an earlier step's output",
    "logs": "the step's input: the batch's log or an earlier step's output",
    "output": "the step's folder (OUTDIR/<log>/NN_<step>/)",
    "overwrite": "a batch replaces its own outputs",
    "progress": "a batch shows one bar of its own",
    "workers": "a batch gives each log its share of the cores",
    "format": "a step that writes a log writes MCAP (convert's format is a key)",
}

#: commands without a batch step, and why
NO_STEP = {
    "play": "replays in real time to a viewer: nothing for a batch to wait for",
    "import": "reads a folder of images, not a log: a batch runs over logs",
    "view": "a recording of many logs at once, for a person to look at: run it on the "
            "batch's outputs",
}

#: command -> its golden job (building the job from the request)
GOLDEN: dict[str, Any] = {
    "calibrate": lambda request: Calibrate("calibrate", request),
    "resync": lambda request: Resync("resync", request),
    "process": lambda request: Process("edges", request, processors=("edges",)),
}

#: commands without a golden job, and why
NO_GOLDEN = {
    "throttle": "copies frames as stored: the output's summary is all it would compare, and "
                "process (whose throttle is the same processor) has a job",
    "convert": "byte-for-byte copies, checked by round trips over every format "
               "(tests/camlog/logs/test_convert.py)",
    "export": "image files of one topic, checked against the log by tests/camlog/cli",
    "info": "a summary that every golden job's artifacts already hold (log_summary)",
    "check": "drift windows of a long log: the golden logs are short and never drift",
    "play": "real-time pacing: its wall-clock timing is not a regression artifact",
    "import": "its input is a folder of images, not a golden log",
    "view": "rerun's recordings change with rerun; the docs' view examples read them back",
}

#: (command, field) -> the fields it needs beside it, for the request's own checks
COMPANIONS: dict[tuple[str, str], dict[str, Any]] = {
    ("calibrate", "left"): {"right": "/b"},
    ("calibrate", "right"): {"left": "/a"},
    ("calibrate", "check"): {"calibration": ("left.yaml",)},
    ("check", "size"): {"square": 0.01},
    ("check", "square"): {"size": "7x6"},
}


def word(arg: Arg) -> str:
    """A command-line word the option's type accepts."""
    if arg.choices:
        return arg.choices[-1]
    return "/a,/b" if arg.type is namespaces else "3"


def test_every_command_is_listed() -> None:
    assert set(COMMANDS) == set(STEPS) | set(NO_STEP)
    assert set(COMMANDS) == set(GOLDEN) | set(NO_GOLDEN)
    assert not set(STEPS) & set(NO_STEP)
    assert {kind.request for kind in STEPS.values()} == \
        {COMMANDS[c][0] for c in COMMANDS if c not in NO_STEP}


CASES = [pytest.param(command, field, id=f"{command}-{field.name}")
         for command, (request, _argv) in COMMANDS.items() for field in request_fields(request)]


@pytest.mark.parametrize(("command", "field"), CASES)
def test_the_command_line_takes_the_field(command: str, field: Field[Any]) -> None:
    arg = arg_of(field)
    extra: list[str] = []
    if arg.flags:
        extra = [arg.flags[-1]]
        if arg.action in ("store", "append", "extend") and arg.nargs != "?":
            extra.append(word(arg))
    args = build_parser([command]).parse_args([command, *COMMANDS[command][1], *extra])
    value = getattr(args, field.name)
    assert value is not None and value != field.default, (command, field.name, value)


def _typed(arg: Arg) -> Any:
    """The option's value as a pipeline gives it (a number as a number)."""
    if arg.action in ("store_true", "store_const"):
        return arg.action == "store_true"
    text = word(arg)
    value: Any = text
    if arg.type is not None and not arg.choices and arg.type is not namespaces:
        value = 3
    return [value] if arg.action in ("append", "extend") or arg.nargs == "+" else value


def _with(command: str, field: Field[Any], value: Any) -> dict[str, Any]:
    """``field = value`` and the fields a request of ``command`` needs beside it."""
    required = {"size": "7x6", "square": 0.01, "topic": "/c/image_raw"}
    return {**{f.name: required[f.name] for f in request_fields(COMMANDS[command][0])
               if f.default is dataclasses.MISSING},
            field.name: value, **COMPANIONS.get((command, field.name), {})}


@pytest.mark.parametrize(("command", "field"), CASES)
def test_a_pipeline_step_takes_the_field(command: str, field: Field[Any]) -> None:
    if command in NO_STEP:
        assert command not in STEPS
        return
    arg = arg_of(field)
    if not arg.batch:
        assert field.name in SET_BY_THE_BATCH
        assert field.name not in STEPS[command].keys
        return
    table = {k: list(v) if isinstance(v, tuple) else v
             for k, v in _with(command, field, _typed(arg)).items()}
    processors = {"process": {"edges": True}, "throttle": {"every": 2}}.get(command, {})
    (step,) = parse_pipeline({"steps": [{"run": command, **table, **processors}]},
                             "p.toml").steps
    assert getattr(step.request, field.name) == table_value(arg, _typed(arg))


@pytest.mark.parametrize(("command", "field"), CASES)
def test_a_golden_job_takes_the_field(command: str, field: Field[Any]) -> None:
    if command in NO_GOLDEN:
        assert command not in GOLDEN
        return
    arg = arg_of(field)
    value = table_value(arg, _typed(arg)) if arg.batch else field.default
    values = {k: tuple(v) if isinstance(v, list) else v
              for k, v in _with(command, field, value).items()}
    job = GOLDEN[command](COMMANDS[command][0](**values))
    assert getattr(job.request, field.name) == value

def test_a_request_error_is_worded_for_each_place() -> None:
    from camlog.errors import PipelineError
    from camlog.requests.fields import RequestError

    with pytest.raises(RequestError) as cli:
        CalibrateRequest(size="7x6", square=0.01, left="/a")
    assert str(cli.value) == "stereo needs both --left and --right"
    with pytest.raises(PipelineError) as batch:
        parse_pipeline({"steps": [{"run": "calibrate", "size": "7x6", "square": 0.01,
                                   "left": "/a"}]}, "p.toml")
    assert str(batch.value) == "p.toml: steps[0]: calibrate: stereo needs both left and right"


@pytest.mark.parametrize(("table", "message"), [
    ({"size": "7x6", "square": -1}, "calibrate: square: expected a number > 0, got -1"),
    ({"size": "7x6", "square": "x"}, "calibrate: square: expected a number, got 'x'"),
    ({"size": "7x6", "square": 0.01, "model": "pinhole"},
     "calibrate: model: expected one of plumb_bob, "),
    ({"size": "7x6", "square": 0.01, "check": "yes"},
     "calibrate: check: expected true or false, got 'yes'"),
    ({"size": 7, "square": 0.01}, "calibrate: size: expected text, got 7"),
    ({"square": 0.01}, "calibrate: give size"),
    ({"size": "7x6", "square": 0.01, "check": True},
     "calibrate: check needs calibration FILE"),
])
def test_pipeline_values_are_checked_with_the_step_and_key(table: dict[str, Any],
                                                           message: str) -> None:
    from camlog.errors import PipelineError

    with pytest.raises(PipelineError, match=message.replace("(", r"\(")):
        parse_pipeline({"steps": [{"run": "calibrate", **table}]}, "p.toml")


def test_the_parser_keeps_field_names_as_dests() -> None:
    args = build_parser(["calibrate"]).parse_args(
        ["calibrate", "in.mcap", "-s", "7x6", "-q", "0.01", "--camera_name", "n"])
    assert isinstance(args, argparse.Namespace)
    assert {f.name for f in request_fields(CalibrateRequest)} <= set(vars(args))
