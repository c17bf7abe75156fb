"""The requests of the commands that derive a log from a log: ``resync``, ``process`` and
``throttle``.

The processors of ``process`` and ``throttle`` are declared by :mod:`processors.registry`;
each of their options is a field of the request, made from that declaration
(:func:`processor_fields`), so that the command line and a pipeline step take them as they
take any other option. A processor is chosen by its flag field (``edges``; ``rectify``
holds its calibration file), or, without a flag (throttle), by giving any of its options;
the request holds the chosen processors configured (:attr:`ProcessRequest.processors`).
This is the edge where a calibration file named by an option is read: processors receive
the camera model, never a path.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

from processors.calibration.patterns import PATTERNS
from processors.errors import OptionValueError
from processors.registry import SPECS, spec_of
from processors.spec import Configured, Option, OptionKind, ProcessorSpec
from replay.format_names import STILL_CODECS
from replay.storage import Location
from replay.topics import RESYNC_PREFIX

from . import fields as common
from .fields import RequestError, option, required
from .values import ESTIMATED, bounded_int, name, number, offset_value, output_path, positive

if TYPE_CHECKING:
    from processors.calibration.board import Board

__all__ = ["CHAPTER_NS", "ProcessRequest", "ResyncRequest", "ThrottleRequest",
           "configure_values", "option_error", "processor_fields", "resolve_value"]

T = TypeVar("T")

#: the namespace of the chapter's nodes (``/image_converter/edges`` ...)
CHAPTER_NS = "/image_converter"


# --- processor options as request fields --------------------------------------------------

def _field_name(spec: ProcessorSpec, option_name: str) -> str:
    """The request field of one of ``spec``'s options: the flag field holds the primary
    option; a flagged processor's other options are ``{processor}_{option}``."""
    if not spec.flag:
        return option_name
    return spec.name if option_name == spec.primary else f"{spec.name}_{option_name}"


def _help(opt: Option) -> str:
    default = "" if opt.default is None else f" (default {opt.default:g})" \
        if isinstance(opt.default, int | float) else f" (default {opt.default})"
    return opt.help + default


def _outputs(spec: ProcessorSpec) -> str:
    if not spec.outputs:
        return ""
    return " -> " + "; ".join(f"NS/{o.name} ({o.msgtype.rpartition('/')[2]}: {o.help or o.label})"
                              for o in spec.outputs)


def _value_type(opt: Option) -> Callable[[str], Any] | None:
    """Numbers are read as text, then by the option (its errors name the processor)."""
    return str if opt.kind in (OptionKind.INT, OptionKind.FLOAT) else None


def processor_fields(specs: Sequence[ProcessorSpec]) -> Callable[[type[T]], type[T]]:
    """A class decorator (under ``@dataclass``): one request field per processor flag and
    per option of ``specs``, listed under each processor's heading."""
    def add(cls: type[T]) -> type[T]:
        annotations = dict(inspect.get_annotations(cls))
        for spec in specs:
            heading = spec.title or spec.name
            about = spec.summary if not spec.flag and not spec.outputs else ""
            if spec.flag:
                help_ = f"{spec.summary}{_outputs(spec)}"
                if spec.primary:
                    primary = spec.option(spec.primary)
                    made = option(None, spec.cli_flag, metavar=primary.metavar or "VALUE",
                                  type=_value_type(primary), help=help_, group=heading)
                else:
                    made = option(False, spec.cli_flag, action="store_true", help=help_,
                                  group=heading)
                annotations[spec.name] = "Any"
                setattr(cls, spec.name, made)
            for opt in spec.options:
                if opt.name == spec.primary:
                    continue
                field_name = _field_name(spec, opt.name)
                annotations[field_name] = "Any"
                setattr(cls, field_name, option(
                    None, opt.cli_flag, metavar=opt.metavar or opt.name.upper(),
                    type=_value_type(opt), help=_help(opt), group=heading, group_help=about,
                    exclusive=spec.name if opt.name in spec.exclusive else "",
                    key=f"{spec.name}.{opt.name}" if spec.flag else opt.name))
        cls.__annotations__ = annotations
        return cls
    return add


def resolve_value(spec: ProcessorSpec, opt: Option, value: Any) -> Any:
    """The typed value of ``opt`` given as text, a number or a path (None stays None)."""
    if value is None:
        return None
    if opt.kind is OptionKind.CAMERA_INFO and isinstance(value, str | Path):
        from replay.calibration_yaml import load_calibration

        return load_calibration(Path(value)).camera_info
    if isinstance(value, str) and opt.kind in (OptionKind.INT, OptionKind.FLOAT):
        try:
            return opt.parse_text(value)
        except ValueError as err:
            raise OptionValueError(spec.name, (opt.name,), str(err)) from None
    if opt.kind is OptionKind.FLOAT and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def configure_values(spec: ProcessorSpec, values: Mapping[str, Any]) -> Configured:
    """``spec`` configured from user values (option name -> text, number, path or None)."""
    typed = {name: resolve_value(spec, spec.option(name), value)
             for name, value in values.items()}
    return spec.configure(typed)


def option_error(request: type, err: OptionValueError) -> RequestError:
    """A processor's option error as the request's: its options named as the request's
    fields (``--low`` on the command line, ``edges.low`` in a pipeline)."""
    spec = spec_of(err.processor)
    known = {o.name for o in spec.options}
    names = ", ".join("{" + _field_name(spec, n) + "}" if n in known else n
                      for n in err.options)
    problem = err.problem.replace("{", "{{").replace("}", "}}")
    return RequestError(request, f"{names or '{' + spec.name + '}'}: {problem}")


def _chosen(request: Any, specs: Sequence[ProcessorSpec]) -> tuple[Configured, ...] | None:
    """The processors the request's processor fields choose, configured (None: no processor
    field is set)."""
    chosen, touched = [], False
    for spec in specs:
        values = {o.name: getattr(request, _field_name(spec, o.name)) for o in spec.options
                  if o.name != spec.primary}
        given = [name for name, value in values.items() if value is not None]
        if spec.flag:
            flag = getattr(request, spec.name)
            if spec.primary:
                values[spec.primary] = flag
            if flag is None or flag is False:
                if given:
                    raise RequestError(type(request), f"{{{_field_name(spec, given[0])}}} "
                                                      f"needs {{{spec.name}}}")
                continue
        elif not given:
            continue
        touched = True
        try:
            chosen.append(configure_values(spec, values))
        except OptionValueError as err:
            raise option_error(type(request), err) from None
    return tuple(chosen) if touched else None

@dataclass(frozen=True, kw_only=True)
class ResyncRequest:
    """Pair and re-stamp the images of two unsynchronised cameras; measure the offset
    between their stamps from what they saw."""

    epilog: ClassVar[str] = (
        "Pairs: |right - left| <= slop, each frame used once, as many pairs as possible, then "
        "the smallest total stamp difference (ties to the earlier frame). Each pair is "
        "re-stamped with the later of its two stamps and written to "
        "PREFIX/{left,right}/{image_raw,camera_info}; PREFIX/offset_s (PointStamped, x = "
        "right - left in s) per pair and PREFIX/stats (JSON) summarise the pairing. Every "
        "input topic is kept. "
        "Offsets: --estimate-offset measures how much later the right camera stamps an "
        "instant than the left from the images: from a moving board both see (--size, "
        "--square), else from natural features of a moving rig (its calibration from the "
        "log's camera_info or --calibration); it prints the offset ± sigma and the frames "
        "that carried it, and writes it to --offset-file. --offset MS|estimated|FILE.json "
        "moves the right camera's stamps back by the offset before pairing."
    )

    log: Location = common.input_log()
    output: Path | None = common.output(default=None)
    left: str = option("/unsynced/left", "--left", type=name, metavar="NS",
                       help="left camera namespace with image_raw[/compressed] and camera_info, "
                            "or its image topic (default /unsynced/left)")
    right: str = option("/unsynced/right", "--right", type=name, metavar="NS",
                        help="right camera namespace or its image topic (default "
                             "/unsynced/right)")
    slop: float | None = option(None, "--slop", type=number(low=0.0, high=3600.0),
                                metavar="SEC",
                                help="largest |right - left| stamp difference of a pair "
                                     "(default: half the median frame period)")
    out_prefix: str = option(RESYNC_PREFIX, "--out-prefix", type=name, metavar="NS",
                             help=f"namespace of the re-stamped topics (default "
                                  f"{RESYNC_PREFIX})")
    estimate_offset: bool = option(
        False, "--estimate-offset", action="store_true", batch=False,
        help="measure the offset between the cameras' stamps from the images, print it and "
             "write --offset-file; no log is written unless -o is given too")
    offset: float | str | None = option(
        None, "--offset", type=offset_value, metavar="MS|estimated|FILE",
        help="move the right camera's stamps back by this offset before pairing: "
             "milliseconds, 'estimated' (measured from the images, as --estimate-offset "
             "does) or an offset file written before")
    offset_file: Path | None = option(
        None, "--offset-file", type=output_path, metavar="FILE", batch=False,
        help="where the measured offset is written (JSON; default OUT_offset.json beside "
             "the output, or LOG_offset.json in the working folder)")
    size: str | None = option(None, "-s", "--size", metavar="COLSxROWS",
                              help="a board in view for the offset: its size in inner "
                                   "corners, e.g. 7x6 (without it: natural features)")
    square: float | None = option(None, "-q", "--square", type=positive, metavar="M",
                                  help="the board's square side in metres")
    pattern: str = option("chessboard", "-p", "--pattern", choices=PATTERNS,
                          help="the board's kind (default chessboard)")
    calibration: Path | None = option(
        None, "--calibration", type=Path, metavar="DIR",
        help="natural features: the pair's calibration, a calibrate output folder (left.yaml "
             "and right.yaml) instead of the log's camera_info")
    max_offset: float = option(0.25, "--max-offset", type=number(above=0.0, high=5.0),
                               metavar="SEC",
                               help="board: search the offset within ±SEC (default 0.25)")
    format: str | None = common.log_format()
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    workers: int | None = common.workers()
    progress: bool | None = common.progress()

    def __post_init__(self) -> None:
        if (self.size is None) != (self.square is None):
            raise RequestError(ResyncRequest, "a board needs both {size} and {square}")
        if self.estimate_offset and self.offset is not None and self.offset != ESTIMATED:
            raise RequestError(ResyncRequest, "{estimate_offset} measures the offset; with "
                                              "{offset} given, leave it out")

    @property
    def measures(self) -> bool:
        """Whether the offset is measured from the images."""
        return self.estimate_offset or self.offset == ESTIMATED

    def board(self) -> Board | None:
        """The board in view (None: natural features)."""
        from processors.calibration.board import make_board

        if self.size is None or self.square is None:
            return None
        return make_board(self.size, self.square, self.pattern)


@dataclass(frozen=True, kw_only=True)
@processor_fields(SPECS)
class ProcessRequest:
    """Run image processors over image topics of a log. ``processors``: those the processor
    fields choose (flags on the command line, keys in a pipeline), else as given; ``thin``:
    the processors only choose frames, which are copied as stored (``throttle``)."""

    epilog: ClassVar[str] = (
        "Every input message is copied through unchanged (unless --drop-input); outputs carry "
        "the processed frame's header and log time. Outputs of TOPIC go to NS/OUTPUT, NS "
        "being TOPIC's namespace (/cam for /cam/image_raw) unless --output-ns says otherwise; "
        "the log records which processor wrote each output and how `camlog view` shows it."
    )

    log: Location = common.input_log()
    output: Path = common.output()
    topic: tuple[str, ...] = required(
        "--topic", type=name, action="append", metavar="T",
        help="image topic to process (Image or CompressedImage, e.g. /cam/image_raw or "
             "/cam/image_raw/compressed); repeat it for several cameras")
    output_ns: str | None = option(
        None, "--output-ns", metavar="NS",
        help=f"namespace of the outputs; {{ns}} stands for the input's (e.g. /processed{{ns}}); "
             f"{CHAPTER_NS} gives the chapter's topic names")
    compress: str | None = option(None, "--compress", choices=STILL_CODECS,
                                  help="write image outputs as CompressedImage on "
                                       "TOPIC/compressed")
    drop_input: bool = option(False, "--drop-input", "--topics-only", action="store_true",
                              help="write only the processors' output topics, not the input's")
    max_frames: int | None = option(None, "--max-frames", type=bounded_int(1, None),
                                    metavar="N",
                                    help="stop after N frames of each topic (quick runs)")
    workers: int | None = common.workers()
    format: str | None = common.log_format()
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    progress: bool | None = common.progress()
    processors: tuple[Configured, ...] = ()
    thin: bool = False

    def __post_init__(self) -> None:
        chosen = _chosen(self, SPECS)
        if chosen is not None:
            object.__setattr__(self, "processors", chosen)
        if len(set(self.topic)) != len(self.topic):
            raise RequestError(ProcessRequest, "give each {topic} once")
        if self.compress is not None and self.compress not in STILL_CODECS:
            raise RequestError(ProcessRequest, f"unknown {{compress}} {self.compress!r} (use "
                                               f"{' or '.join(STILL_CODECS)})")
        for configured in self.processors:
            if len(self.topic) > 1 and any(o.kind is OptionKind.CAMERA_INFO
                                           for o in configured.spec.options):
                raise RequestError(ProcessRequest, f"{configured.name} takes one camera's "
                                                   "calibration: process one {topic} with it "
                                                   "per run")
        if self.thin and any(not c.spec.selects for c in self.processors):
            raise RequestError(ProcessRequest, "thinning passes frames through: use only "
                                               "selecting processors")

    def require_processors(self) -> None:
        """The run's rule: a processor that computes outputs (or, thinning, one that
        selects frames)."""
        if self.thin and not self.processors:
            selecting = [o.name for s in SPECS if s.selects and not s.flag for o in s.options]
            raise RequestError(ProcessRequest,
                               "give " + " or ".join(f"{{{n}}}" for n in selecting))
        if not self.thin and not any(not c.spec.selects for c in self.processors):
            raise RequestError(ProcessRequest, "choose at least one of " + ", ".join(
                f"{{{s.name}}}" for s in SPECS if s.flag))


@dataclass(frozen=True, kw_only=True)
@processor_fields([spec_of("throttle")])
class ThrottleRequest:
    """Thin topics of a log to every N-th message or at most HZ, copied as stored (the
    registry's ``throttle`` processor, configured in ``processors``)."""

    log: Location = common.input_log()
    output: Path = common.output(checked=False)
    topic: tuple[str, ...] = required(
        "--topic", action="append", metavar="T",
        help="topic to thin (images, camera_info or other stamped messages); repeat it for "
             "several (each is thinned by its own stamps)")
    format: str | None = common.log_format()
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    progress: bool | None = common.progress()
    processors: tuple[Configured, ...] = ()

    def __post_init__(self) -> None:
        chosen = _chosen(self, [spec_of("throttle")])
        if chosen is not None:
            object.__setattr__(self, "processors", chosen)

    def processing(self) -> ProcessRequest:
        """The ``process`` request that thins the topics."""
        return ProcessRequest(log=self.log, output=self.output, topic=self.topic,
                              processors=self.processors, thin=True, format=self.format,
                              overwrite=self.overwrite, recover=self.recover,
                              progress=self.progress)

