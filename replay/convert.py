"""``camlog convert``: copy a log into another format, filtered, images optionally re-encoded.

Messages are copied raw (``write_raw``): between formats with the same serialization the
bytes are unchanged, and between CDR (MCAP, rosbag2) and ROS1 they are re-serialized by
rosbags. Only with ``compress`` or ``decompress`` are images decoded, and their topics
renamed as image_transport names them: ``T`` (Image) <-> ``T/compressed`` (CompressedImage).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from .atomic import check_not_input
from .codec import decode_compressed, encode_compressed, ros2_typestore, serialize
from .errors import EncodingError, LogReadError, OptionError, TopicError
from .formats import open_reader, open_writer
from .formats.base import LogReader, RawMessage
from .messages import MSGTYPES, CompressedImage, Image
from .selection import select_topics, window_ns

__all__ = ["COMPRESSIONS", "ConvertResult", "convert_log", "renamed_topics"]

COMPRESSIONS = ("jpeg", "png")
IMAGE = MSGTYPES[Image]
COMPRESSED = MSGTYPES[CompressedImage]


@dataclass(frozen=True)
class ConvertResult:
    """What :func:`convert_log` wrote: message counts, renamed topics, warnings."""

    output: Path
    format_name: str
    messages: int
    reencoded: int
    renamed: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    wall_s: float = 0.0


def renamed_topics(
    msgtypes: dict[str, str], *, compress: str | None, decompress: bool
) -> dict[str, str]:
    """Input image topic -> output topic for the images that are re-encoded.

    >>> renamed_topics({"/c/image_raw": IMAGE}, compress="jpeg", decompress=False)
    {'/c/image_raw': '/c/image_raw/compressed'}
    >>> renamed_topics({"/c/image_raw/compressed": COMPRESSED}, compress=None, decompress=True)
    {'/c/image_raw/compressed': '/c/image_raw'}
    """
    if compress is not None and decompress:
        raise OptionError("--compress and --decompress exclude each other")
    if compress is not None and compress not in COMPRESSIONS:
        raise OptionError(f"unknown compression {compress!r} (use {' or '.join(COMPRESSIONS)})")
    renamed: dict[str, str] = {}
    for topic, msgtype in msgtypes.items():
        if compress is not None and msgtype == IMAGE:
            renamed[topic] = f"{topic}/compressed"
        elif decompress and msgtype == COMPRESSED:
            renamed[topic] = topic.removesuffix("/compressed") or topic
    kept = set(msgtypes) - set(renamed)
    clashes = sorted(out for out in renamed.values() if out in kept)
    if clashes:
        raise TopicError(f"the output would have two {clashes[0]} topics (the log has both "
                         "forms of this image topic): leave one out with --topics")
    return renamed


def _msgdef(reader: LogReader, topic: str) -> str:
    """The input's definition for types rosbags does not know (the writer generates the
    others, in the schema encoding it declares)."""
    info = reader.topics[topic]
    return "" if info.msgtype in ros2_typestore().types else info.msgdef


def _reencode(reader: LogReader, raw: RawMessage, topic: str, *, compress: str | None,
              serialization: str) -> RawMessage:
    message = reader.decode(raw)
    try:
        if isinstance(message, Image) and compress is not None:
            out: Image | CompressedImage = encode_compressed(message, compress)
        elif isinstance(message, CompressedImage):
            out = decode_compressed(message)
        else:
            raise EncodingError(f"unexpected {type(message).__name__}")
    except EncodingError as err:
        raise EncodingError(f"{reader.path}: topic {raw.topic} at log time "
                            f"{raw.log_time_ns}: {err}") from None
    msgtype = MSGTYPES[type(out)]
    return RawMessage(topic, msgtype, raw.log_time_ns, serialize(out, serialization),
                      serialization)


def convert_log(
    input_path: Path,
    output: Path,
    *,
    fmt: str | None = None,
    topics: Sequence[str] | None = None,
    start_s: float | None = None,
    end_s: float | None = None,
    compress: str | None = None,
    decompress: bool = False,
    overwrite: bool = False,
    recover: bool = False,
    progress: bool | None = None,
) -> ConvertResult:
    """Write the chosen topics and time window of ``input_path`` to ``output`` atomically.

    ``fmt`` defaults from the output name (``.mcap``, ``.bag``, a directory for rosbag2).
    """
    started = time.perf_counter()
    check_not_input(Path(output), [Path(input_path)])
    with open_reader(input_path, recover=recover) as reader:
        if reader.message_count == 0:
            raise LogReadError(f"{reader.path} is empty (no messages)")
        chosen = select_topics(reader.topics, topics, where=str(reader.path))
        names = chosen if chosen is not None else sorted(reader.topics)
        renamed = renamed_topics({t: reader.topics[t].msgtype for t in names},
                                 compress=compress, decompress=decompress)
        start_ns, end_ns = window_ns(reader.start_ns, start_s, end_s)
        total = sum(reader.topics[t].count for t in names)
        written = reencoded = 0
        with open_writer(output, fmt=fmt, overwrite=overwrite,
                         inputs=[input_path]) as writer, \
                tqdm(total=total, unit="msg", desc="convert", leave=False,
                     disable=None if progress is None else not progress) as bar:
            for name, values in reader.metadata.items():
                writer.set_metadata(name, values)
            for raw in reader.raw_messages(chosen, start_ns, end_ns):
                if raw.topic in renamed:
                    writer.write_raw(_reencode(reader, raw, renamed[raw.topic],
                                               compress=compress,
                                               serialization=writer.serialization))
                    reencoded += 1
                else:
                    writer.write_raw(raw, msgdef=_msgdef(reader, raw.topic))
                written += 1
                bar.update()
            format_name = writer.format_name
        warnings = list(reader.warnings)
    return ConvertResult(output, format_name, written, reencoded, renamed, warnings,
                         time.perf_counter() - started)
