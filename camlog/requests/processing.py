"""The requests of the commands that derive a log from a log: ``resync``, ``process`` and
``throttle``.

The processors of ``process`` and ``throttle`` are declared by :mod:`processors.registry`
(their flags and pipeline keys are generated from it); a request holds them configured.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from processors.calibration.patterns import PATTERNS
from processors.spec import Configured
from replay.storage import Location
from replay.topics import RESYNC_PREFIX

from . import fields as common
from .fields import RequestError, option, required
from .values import ESTIMATED, bounded_int, name, number, offset_value, output_path, positive

if TYPE_CHECKING:
    from processors.calibration.board import Board

__all__ = ["CHAPTER_NS", "COMPRESSIONS", "ProcessRequest", "ResyncRequest", "ThrottleRequest"]

#: the namespace of the chapter's nodes (``/image_converter/edges`` ...)
CHAPTER_NS = "/image_converter"
#: formats image outputs may be compressed to
COMPRESSIONS = ("jpeg", "png")

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
class ProcessRequest:
    """Run image processors over image topics of a log. ``processors`` come from the
    processor flags (command line) or keys (pipeline); ``thin``: the processors only choose
    frames, which are copied as stored (``throttle``)."""

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
    compress: str | None = option(None, "--compress", choices=COMPRESSIONS,
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
    processors: tuple[Configured, ...] = ()
    thin: bool = False


@dataclass(frozen=True, kw_only=True)
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
    processors: tuple[Configured, ...] = ()

    def processing(self) -> ProcessRequest:
        """The ``process`` request that thins the topics."""
        return ProcessRequest(log=self.log, output=self.output, topic=self.topic,
                              processors=self.processors, thin=True, format=self.format,
                              overwrite=self.overwrite, recover=self.recover)

