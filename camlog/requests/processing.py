"""The requests of the commands that derive a log from a log: ``resync``, ``process`` and
``throttle``.

The processors of ``process`` and ``throttle`` are declared by :mod:`processors.registry`
(their flags and pipeline keys are generated from it); a request holds them configured.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from processors.spec import Configured
from replay.storage import Location
from replay.topics import RESYNC_PREFIX

from . import fields as common
from .fields import option, required
from .values import bounded_int, name, number

__all__ = ["CHAPTER_NS", "COMPRESSIONS", "ProcessRequest", "ResyncRequest", "ThrottleRequest"]

#: the namespace of the chapter's nodes (``/image_converter/edges`` ...)
CHAPTER_NS = "/image_converter"
#: formats image outputs may be compressed to
COMPRESSIONS = ("jpeg", "png")

@dataclass(frozen=True, kw_only=True)
class ResyncRequest:
    """Pair and re-stamp the images of two unsynchronised cameras."""

    epilog: ClassVar[str] = (
        "Pairs: |right - left| <= slop, each frame used once, as many pairs as possible, then "
        "the smallest total stamp difference (ties to the earlier frame). Each pair is "
        "re-stamped with the later of its two stamps and written to "
        "PREFIX/{left,right}/{image_raw,camera_info}; PREFIX/offset_s (PointStamped, x = "
        "right - left in s) per pair and PREFIX/stats (JSON) summarise the pairing. Every "
        "input topic is kept."
    )

    log: Location = common.input_log()
    output: Path = common.output()
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
    format: str | None = common.log_format()
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()


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

