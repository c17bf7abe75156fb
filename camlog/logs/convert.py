"""``camlog convert``: copy a log into another format, filtered, images optionally re-encoded.

Messages are copied raw (``write_raw``): between formats with the same serialization the
bytes are unchanged, between CDR (MCAP, rosbag2) and ROS1 they are re-serialized by
rosbags, and channels of other serializations (Foxglove protobuf or JSON, any schema) are
copied untouched into MCAP. Only with ``compress`` or ``decompress`` are images decoded,
and their topics renamed as image_transport names them: ``T`` (Image) <-> ``T/compressed``
(CompressedImage), or ``T/video`` (CompressedVideo). See :mod:`replay.reencode` for what
each topic becomes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from replay.atomic import check_not_input
from replay.errors import LogReadError, OptionError, ReplayError, TopicError
from replay.format_names import STILL_CODECS, VIDEO_CODEC_NAMES
from replay.formats import format_for_output, open_reader, open_writer
from replay.formats.base import LogReader
from replay.messages import MSGTYPES, CameraInfo, CompressedImage, CompressedVideo, Image, Message
from replay.progress import progress_bar
from replay.selection import select_topics, window_ns
from replay.wire import record_msgtype, ros2_typestore

from ..requests.logs import ConvertRequest

if TYPE_CHECKING:
    from replay.reencode import TopicReencoder

#: camera types stored in Foxglove's schemas under ``--profile foxglove``
FOXGLOVE_CAMERA_TYPES = frozenset(MSGTYPES[kind] for kind in (Image, CompressedImage, CameraInfo))

__all__ = ["COMPRESSIONS", "ConvertResult", "convert_log", "renamed_topics"]

COMPRESSIONS = (*STILL_CODECS, *VIDEO_CODEC_NAMES)
IMAGE = MSGTYPES[Image]
COMPRESSED = MSGTYPES[CompressedImage]
VIDEO = MSGTYPES[CompressedVideo]


@dataclass(frozen=True)
class ConvertResult:
    """What :func:`convert_log` wrote: message counts, renamed topics, warnings, and the
    PSNR (dB) of every topic re-encoded as video."""

    output: Path
    format_name: str
    messages: int
    reencoded: int
    renamed: dict[str, str] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    wall_s: float = 0.0
    psnr_db: dict[str, float] = field(default_factory=dict)


def renamed_topics(
    msgtypes: dict[str, str], *, compress: str | None, decompress: bool
) -> dict[str, str]:
    """Input image topic -> output topic for the images that are re-encoded (raw images,
    ROS or Foxglove, to ``T/compressed``, or ``T/video`` for video; back with
    ``decompress``).

    >>> renamed_topics({"/c/image_raw": IMAGE}, compress="jpeg", decompress=False)
    {'/c/image_raw': '/c/image_raw/compressed'}
    >>> renamed_topics({"/c/image_raw/compressed": COMPRESSED}, compress=None, decompress=True)
    {'/c/image_raw/compressed': '/c/image_raw'}
    """
    if compress is not None and decompress:
        raise OptionError("--compress and --decompress exclude each other")
    if compress is not None and compress not in COMPRESSIONS:
        raise OptionError(f"unknown compression {compress!r} (use {', '.join(COMPRESSIONS)})")
    suffix = "/video" if compress in VIDEO_CODEC_NAMES else "/compressed"
    renamed: dict[str, str] = {}
    for topic, msgtype in msgtypes.items():
        kind = record_msgtype(msgtype)
        if compress is not None and kind == IMAGE:
            renamed[topic] = f"{topic}{suffix}"
        elif decompress and kind in (COMPRESSED, VIDEO):
            renamed[topic] = topic.removesuffix("/compressed").removesuffix("/video") or topic
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


def _reencoders(renamed: dict[str, str], compress: str | None,
                crf: int) -> dict[str, TopicReencoder]:
    """A re-encoder per renamed topic (images are decoded only for these)."""
    if not renamed:
        return {}
    from replay.reencode import TopicReencoder

    return {t: TopicReencoder(t, compress, crf) for t in renamed}


def convert_log(request: ConvertRequest) -> ConvertResult:
    """Write the chosen topics and time window of the request's ``input`` to its ``output``
    atomically.

    ``format`` defaults from the output name (``.mcap``, ``.bag``, a directory for rosbag2).
    ``profile="foxglove"`` (MCAP only) stores images, camera models and video in
    Foxglove's schemas, so that Foxglove shows them in its own panels. ``crf`` is the
    video encoder's constant rate factor (``compress`` h264 or h265).
    """
    input_path, output, fmt, topics = request.input, request.output, request.format, \
        request.topics
    start_s, end_s, compress, decompress = (request.start, request.end, request.compress,
                                            request.decompress)
    profile, overwrite, recover = request.profile, request.overwrite, request.recover
    progress, crf = request.progress, request.crf
    started = time.perf_counter()
    check_not_input(Path(output), [Path(input_path)])
    fmt = format_for_output(Path(output), fmt)
    if fmt != "mcap" and (profile != "ros2" or compress in VIDEO_CODEC_NAMES):
        what = f"--compress {compress}" if compress in VIDEO_CODEC_NAMES else f"--profile {profile}"
        raise OptionError(f"{what} writes Foxglove schemas, which only MCAP holds")
    with open_reader(input_path, recover=recover) as reader:
        if reader.message_count == 0:
            raise LogReadError(f"{reader.path} is empty (no messages)")
        chosen = select_topics(reader.topics, topics, where=str(reader.path))
        names = chosen if chosen is not None else sorted(reader.topics)
        renamed = renamed_topics({t: reader.topics[t].msgtype for t in names},
                                 compress=compress, decompress=decompress)
        start_ns, end_ns = window_ns(reader.start_ns, start_s, end_s)
        total = sum(reader.topics[t].count for t in names)
        options: dict[str, Any] = {"profile": profile} if fmt == "mcap" else {}
        codecs = _reencoders(renamed, compress, crf)
        msgdefs = {t: _msgdef(reader, t) for t in names}
        written = reencoded = 0
        with open_writer(output, fmt=fmt, overwrite=overwrite, inputs=[input_path],
                         **options) as writer, \
                progress_bar(total=total, unit="msg", desc="convert", progress=progress) as bar:
            for name, values in reader.metadata.items():
                writer.set_metadata(name, values)
            for raw in reader.raw_messages(chosen, start_ns, end_ns):
                bar.update()
                codec = codecs.get(raw.topic)
                out: Message | bool | None = False
                if codec is not None:
                    try:
                        out = codec(reader.decode(raw))
                    except ReplayError as err:  # e.g. a buffer too short for its size
                        out = codec.failed(err)
                if out is None:
                    continue
                if out is False and profile == "foxglove" and \
                        record_msgtype(raw.msgtype) in FOXGLOVE_CAMERA_TYPES:
                    out = reader.decode(raw)
                if out is False:
                    writer.write_raw(raw, msgdef=msgdefs[raw.topic])
                else:
                    assert not isinstance(out, bool)
                    topic = renamed.get(raw.topic, raw.topic)
                    writer.write(topic, out, log_time_ns=raw.log_time_ns)
                    reencoded += topic != raw.topic
                written += 1
            format_name = writer.format_name
            warnings = list(reader.warnings) + writer.warnings
        for codec in codecs.values():
            warnings += codec.notes()
    actual = {t: out for t, out in renamed.items() if codecs[t].chosen is not None}
    psnr = {actual[t]: c.psnr_mean_db for t, c in codecs.items()
            if t in actual and c.psnr_mean_db is not None}
    return ConvertResult(output, format_name, written, reencoded, actual, warnings,
                         time.perf_counter() - started, psnr)
