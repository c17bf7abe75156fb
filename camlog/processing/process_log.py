"""Stream one image topic of a log through processors and write a new log.

The reader's raw messages are copied through untouched (``write_raw``: no decode or
re-encode). Frames of the processed topic are decoded on the reading thread (a header and
a view of the pixel buffer) and run through the processors on a thread pool (OpenCV and
numpy release the GIL); outputs are serialized on the workers too and written in frame
order. At most ``in_flight`` frames are pending, so memory does not grow with the log.
"""

from __future__ import annotations

import os
import time
from collections import deque
from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2

from processors.base import Processor
from processors.errors import ProcessorError
from processors.throttle import KeepAll, Throttle
from replay.atomic import check_not_input
from replay.codec import decode_compressed, encode_compressed, msgtype_of, serialize
from replay.errors import ReplayError
from replay.formats import RawMessage, open_reader, open_writer
from replay.messages import CompressedImage, Image, Message
from replay.storage import Location, local_paths

from ..errors import ProcessingError, UsageError
from .checks import (
    IMAGE_TYPES,
    require_free_topics,
    require_messages,
    require_topic,
)

COMPRESSIONS = ("jpeg", "png")


@dataclass(frozen=True)
class ProcessResult:
    """What :func:`process_log` did."""

    output: Path
    frames_read: int  # frames of the topic that were read
    frames_processed: int  # after throttling
    messages_written: int
    wall_s: float

    @property
    def fps(self) -> float:
        """Frames of the topic read per second of wall time."""
        return self.frames_read / self.wall_s if self.wall_s > 0 else 0.0


@dataclass(frozen=True)
class _Job:
    """Everything a worker needs for one frame (no shared mutable state)."""

    processors: tuple[Processor, ...]
    compress: str | None
    serialization: str
    where: str  # "LOG: TOPIC" for error messages

    def __call__(self, frame: Message, log_time_ns: int) -> list[RawMessage]:
        stamp = getattr(frame, "stamp_ns", "?")
        try:
            image = decode_compressed(frame) if isinstance(frame, CompressedImage) else frame
            assert isinstance(image, Image)
            raws = []
            for processor in self.processors:
                for name, output in processor(image):
                    topic, message = name, output
                    if self.compress and isinstance(output, Image):
                        topic = name + "/compressed"
                        message = encode_compressed(output, self.compress)
                    raws.append(RawMessage(topic, msgtype_of(message), log_time_ns,
                                           serialize(message, self.serialization),
                                           self.serialization))
            return raws
        except (ProcessorError, ReplayError, cv2.error) as err:
            text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            raise ProcessingError(f"{self.where}: frame stamped {stamp}: {text}") from None


def output_topics(processors: Sequence[Processor], compress: str | None) -> dict[str, str]:
    """Every topic the processors may write, with its type after compression."""
    topics: dict[str, str] = {}
    for processor in processors:
        for name, kind in processor.outputs().items():
            topic, msgtype = name, kind
            if compress and kind == "sensor_msgs/msg/Image":
                topic, msgtype = name + "/compressed", "sensor_msgs/msg/CompressedImage"
            if topic in topics:
                raise UsageError(f"two processors write {topic}")
            topics[topic] = msgtype
    return topics


def process_log(
    input_path: Location,
    output: Path,
    *,
    topic: str,
    processors: Sequence[Processor],
    throttle: Throttle | None = None,
    compress: str | None = None,
    drop_input: bool = False,
    max_frames: int | None = None,
    fmt: str | None = None,
    overwrite: bool = False,
    workers: int | None = None,
    recover: bool = False,
) -> ProcessResult:
    """Run ``processors`` over ``topic`` of ``input_path`` and write ``output`` atomically.

    The output keeps every input message (unless ``drop_input``) plus the processors'
    outputs, which carry the input frame's log time and header. ``max_frames`` stops after
    that many frames of the topic (and the messages logged before them).
    """
    started = time.perf_counter()
    if not processors:
        raise UsageError("no processor chosen (e.g. --red-pixels, --edges, --rectify)")
    if compress is not None and compress not in COMPRESSIONS:
        raise UsageError(f"unknown compression {compress!r} (use {' or '.join(COMPRESSIONS)})")
    throttle = throttle or KeepAll()
    check_not_input(output, local_paths(input_path))
    new_topics = output_topics(processors, compress)
    with open_reader(input_path, recover=recover) as reader:
        require_messages(reader)
        require_topic(reader, topic, IMAGE_TYPES)
        if not drop_input:
            require_free_topics(reader, new_topics, hint="pass --drop-input to leave the "
                                "input topics out")
        workers = workers or min(4, os.cpu_count() or 1)
        in_flight = 2 * workers + 2
        with open_writer(output, fmt=fmt, overwrite=overwrite,
                         inputs=local_paths(input_path)) as writer:
            job = _Job(tuple(processors), compress, writer.serialization,
                       f"{reader.path}: {topic}")
            for first in reader.raw_messages([topic]):  # fail early; warm up serializers
                job(reader.decode(first), first.log_time_ns)
                break
            read = processed = written = 0
            pending: deque[Future[list[RawMessage]]] = deque()

            def flush(keep: int) -> int:
                count = 0
                while len(pending) > keep:
                    for raw in pending.popleft().result():
                        writer.write_raw(raw)
                        count += 1
                return count

            with ThreadPoolExecutor(workers, thread_name_prefix="camlog-process") as pool:
                try:
                    for raw in reader.raw_messages():
                        if not drop_input:
                            writer.write_raw(raw)
                            written += 1
                        if raw.topic != topic:
                            continue
                        read += 1
                        frame = reader.decode(raw)
                        if throttle.keep(getattr(frame, "stamp_ns", raw.log_time_ns)):
                            processed += 1
                            pending.append(pool.submit(job, frame, raw.log_time_ns))
                            written += flush(in_flight)
                        if max_frames is not None and read >= max_frames:
                            break
                    written += flush(0)
                except BaseException:
                    for future in pending:
                        future.cancel()
                    raise
    return ProcessResult(output, read, processed, written, time.perf_counter() - started)
