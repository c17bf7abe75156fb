"""How a request declares an option once: a dataclass field whose metadata holds an
:class:`Arg` (flags, help, metavar, value type, choices), from which the command line's
arguments and a pipeline step's keys (the field's name) are both made.

The options every log command shares are declared here once (:func:`input_log`,
:func:`recover`, :func:`output`, :func:`overwrite`, :func:`progress`, :func:`workers`,
:func:`log_format`) and reused by each request.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import MISSING, dataclass
from pathlib import Path
from typing import Any

from replay.format_names import WRITE_FORMATS

from ..errors import UsageError
from .values import bounded_int, name, non_negative, output_path

__all__ = ["Arg", "RequestError", "arg_of", "batch_keys", "bind", "connect", "end", "flag_words",
           "input_log", "key_of", "log_format", "option", "output", "overwrite", "port",
           "progress", "recover", "request_fields", "required", "spawn", "start", "topics",
           "viewer_output", "workers"]

#: the metadata key of a field's :class:`Arg`
ARG = "arg"


@dataclass(frozen=True)
class Arg:
    """What the command line needs of one option.

    ``flags`` empty: a positional argument. ``action``: ``store`` (one value, read by
    ``type``), ``store_true``, ``store_const`` (``const`` when the flag is given),
    ``append`` (the flag repeated) or ``extend`` (``nargs`` values). ``exclusive`` names a
    group of options that may not be given together. ``batch`` False: a pipeline step does
    not take it as a key (the batch runner sets it: input, output, overwrite, progress).
    ``required``: the command line needs it although the field has a default (a runner
    sets it otherwise). ``key``: how a pipeline step names it (default: the field's name;
    ``edges.low`` is the key ``low`` of the table ``edges = {...}``). ``group``: the heading
    it is listed under in help (``group_help``: that group's description).
    """

    flags: tuple[str, ...] = ()
    help: str = ""
    metavar: str | None = None
    type: Callable[[str], Any] | None = None
    choices: tuple[Any, ...] | None = None
    action: str = "store"
    nargs: str | None = None
    const: Any = None
    exclusive: str = ""
    batch: bool = True
    required: bool = False
    key: str = ""
    group: str = ""
    group_help: str = ""


def option(default: Any, *flags: str, **arg: Any) -> Any:
    """A request field with default ``default`` (:data:`dataclasses.MISSING`: none) and the
    command-line flags ``flags`` (none: positional); ``arg`` are :class:`Arg`'s other
    fields."""
    metadata = {ARG: Arg(flags, **arg)}
    if default is MISSING:
        return dataclasses.field(metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def required(*flags: str, **arg: Any) -> Any:
    """A request field without a default: the command line and a pipeline step must give
    it."""
    return option(MISSING, *flags, **arg)


def arg_of(field: dataclasses.Field[Any]) -> Arg:
    """The :class:`Arg` of a request field."""
    arg = field.metadata.get(ARG)
    if not isinstance(arg, Arg):
        raise TypeError(f"{field.name} is not declared with camlog.requests.fields.option")
    return arg


def request_fields(request: type) -> tuple[dataclasses.Field[Any], ...]:
    """The declared options of a request class, in declaration order."""
    return tuple(f for f in dataclasses.fields(request) if ARG in f.metadata)


def key_of(field: dataclasses.Field[Any]) -> str:
    """How a pipeline step names a request field: its :attr:`Arg.key`, or its name."""
    return arg_of(field).key or field.name


def batch_keys(request: type) -> frozenset[str]:
    """The keys a pipeline step of ``request`` takes: its fields the runner does not set
    (a dotted key is a key of a table, ``edges.low`` of ``edges = {low = ...}``)."""
    return frozenset(key_of(f) for f in request_fields(request)
                     if arg_of(f).batch and "." not in key_of(f))


class RequestError(UsageError):
    """A command's request is invalid: ``template`` names its options as ``{field}``, which
    read as flags (``--left``) on the command line and as keys (``left``) in a pipeline."""

    def __init__(self, request: type, template: str) -> None:
        self.request = request
        self.template = template
        super().__init__(template)

    def worded(self, word: dict[str, str]) -> str:
        """The message with each ``{field}`` given as ``word[field]``."""
        return self.template.format_map(word)

    def __str__(self) -> str:
        return self.worded(flag_words(self.request))


def flag_words(request: type) -> dict[str, str]:
    """Field name -> how the command line spells it (its first long flag, or its metavar)."""
    words = {}
    for f in request_fields(request):
        arg = arg_of(f)
        longs = [flag for flag in arg.flags if flag.startswith("--")]
        words[f.name] = longs[0] if longs else arg.flags[0] if arg.flags else \
            arg.metavar or f.name.upper()
    return words


# --- the options log commands share ------------------------------------------------------

def input_log(help: str = "input log (never modified)", *, batch: bool = False) -> Any:
    """``LOG``: the log a command reads (a runner sets it in a pipeline or a golden job)."""
    return option(Path(), metavar="LOG", type=Path, help=help, batch=batch)


def recover() -> Any:
    """``--recover``: read a damaged log as far as it can be read."""
    return option(False, "--recover", action="store_true",
                  help="read a damaged log: past damaged chunks (MCAP, ROS1) and the SQLite "
                       "rows that still read (rosbag2), saying what was lost")


def output(help: str = "output log: .mcap, .bag or a rosbag2 directory name", *,
           metavar: str = "OUT", default: Path | None = Path(), checked: bool = True) -> Any:
    """``-o/--output``: where a command writes (a runner sets it); required on the command
    line unless ``default`` is None."""
    return option(default, "-o", "--output", type=output_path if checked else Path,
                  metavar=metavar, help=help, batch=False, required=default is not None)


def overwrite() -> Any:
    """``--overwrite``: replace existing outputs (a batch always replaces its own)."""
    return option(False, "--overwrite", action="store_true", batch=False,
                  help="replace an existing output")


def progress(default: bool | None = None) -> Any:
    """``--no-progress``: hide progress bars (None: shown on a terminal)."""
    return option(default, "--no-progress", action="store_const", const=False, batch=False,
                  help="hide progress bars")


def workers() -> Any:
    """``--workers N``: processing threads (a batch gives each log its share)."""
    return option(None, "--workers", type=bounded_int(1, 256), metavar="N", batch=False,
                  help="processing threads (default: cores)")


def log_format(default_from: str = "OUT", *, batch: bool = False) -> Any:
    """``--format``: the output log format, by default told from the output's name
    (a pipeline step writes MCAP unless ``batch``)."""
    return option(None, "--format", choices=tuple(sorted(WRITE_FORMATS)), batch=batch,
                  help=f"output format (default: from {default_from})")


def topics(help: str = "only these topics (exact names or globs such as '/cam/*'; put the "
                       "option after the log paths)") -> Any:
    """``--topics T…``: the topics a command reads."""
    return option(None, "--topics", nargs="+", action="extend", metavar="T", help=help)


def start(help: str = "start S seconds after the first message") -> Any:
    """``--start S``: seconds after the first message."""
    return option(None, "--start", type=non_negative, metavar="S", help=help)


def end(help: str = "stop S seconds after the first message (exclusive)") -> Any:
    """``--end S``: seconds after the first message (exclusive)."""
    return option(None, "--end", type=non_negative, metavar="S", help=help)


def viewer_output(what: str) -> Any:
    """``-o OUT``: where a viewer command writes instead of streaming (one of ``viewer``)."""
    return option(None, "-o", "--output", type=output_path, metavar="OUT", exclusive="viewer",
                  help=f"write the {what} to OUT", batch=False)


def spawn() -> Any:
    """``--spawn``: start a rerun viewer and stream to it."""
    return option(False, "--spawn", action="store_true", exclusive="viewer", batch=False,
                  help="start a rerun viewer and stream to it")


def connect() -> Any:
    """``--connect URL``: stream to a running viewer."""
    return option(None, "--connect", metavar="URL", exclusive="viewer", batch=False,
                  help="stream to a running viewer (rerun+http://HOST:PORT/proxy or "
                       "HOST:PORT)")


def bind() -> Any:
    """``--bind ADDR``: the address a spawned viewer listens on."""
    return option("127.0.0.1", "--bind", metavar="ADDR", type=name, batch=False,
                  help="with --spawn: the address the viewer listens on (default 127.0.0.1, "
                       "this machine only; 0.0.0.0 for every interface)")


def port() -> Any:
    """``--port N``: the port a spawned viewer listens on."""
    return option(9876, "--port", type=bounded_int(1, 65535), metavar="N", batch=False,
                  help="with --spawn: the port the viewer listens on (default 9876; a viewer "
                       "already there is used)")
