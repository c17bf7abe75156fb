"""Stream image topics of a log through processors and write a new log.

The reader's raw messages are copied through untouched (``write_raw``: no decode or
re-encode). Frames of the processed topics are decoded on the reading thread (a header and
a view of the pixel buffer), selected there in stream order (throttle), and run through the
processors on a thread pool (OpenCV and numpy release the GIL); outputs are serialized on
the workers too and written in frame order. At most ``in_flight`` frames are pending, so
memory does not grow with the log. The output log also gets one record on
:data:`replay.topics.PROCESSED` naming each output topic, its source, its processor
and how it is displayed.
"""

from __future__ import annotations

import os
import time
from collections import deque
from collections.abc import Mapping, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import cv2

from processors.base import Processor
from processors.errors import ProcessorError
from processors.spec import Configured, OptionKind
from processors.throttle import Throttle
from replay._version import VERSION
from replay.atomic import check_not_input
from replay.errors import EncodingError, ReplayError, UnsupportedEncodingError
from replay.formats import LogReader, LogWriter, RawMessage, open_reader, open_writer
from replay.frames import Frame, FrameStream, decode_frame, encode_compressed
from replay.messages import CompressedVideo, Image, Message
from replay.records import ProcessedOutput, ProcessedOutputs
from replay.storage import local_paths
from replay.topics import PROCESSED
from replay.wire import msgtype_of, serialize

from ..errors import ProcessingError, UsageError
from ..requests.processing import ProcessRequest
from .checks import (
    IMAGE_TYPES,
    STAMPED_TYPES,
    require_free_topics,
    require_messages,
    require_topic,
)
from .outputs import COMPRESSIONS, plan_outputs


@dataclass(frozen=True)
class ProcessResult:
    """What :func:`process_log` did (frame counts summed over the processed topics)."""

    output: Path
    frames_read: int  # frames of the topics that were read
    frames_processed: int  # after throttling
    messages_written: int
    wall_s: float
    outputs: tuple[ProcessedOutput, ...] = ()
    undecodable: dict[str, int] = field(default_factory=dict)  # topic -> frames copied only

    @property
    def warnings(self) -> list[str]:
        """One line per topic with frames that did not decode (copied, not processed)."""
        return [f"{topic}: {count} frames did not decode (copied, not processed)"
                for topic, count in sorted(self.undecodable.items())]

    @property
    def fps(self) -> float:
        """Frames of the topics read per second of wall time."""
        return self.frames_read / self.wall_s if self.wall_s > 0 else 0.0


@dataclass(frozen=True)
class _Job:
    """Everything a worker needs for one frame of one topic (no shared mutable state)."""

    stages: tuple[tuple[Processor, Mapping[str, str]], ...]  # processor, output -> topic
    compress: str | None
    serialization: str
    where: str  # "LOG: TOPIC" for error messages

    def __call__(self, frame: Message | Frame, log_time_ns: int) -> list[RawMessage] | None:
        """The serialized outputs of one frame (a still image message is decoded here, on
        the worker; video arrives decoded, in order); None when the frame does not decode."""
        stamp = getattr(frame, "stamp_ns", "?")
        try:
            try:
                image = frame if isinstance(frame, Frame) else FrameStream().decode(frame)
            except UnsupportedEncodingError:
                raise
            except EncodingError:
                return None
            assert image is not None  # still images always give a frame
            raws = []
            for processor, topics in self.stages:
                for name, output in processor(image):
                    message: Message = output
                    if self.compress and isinstance(output, Image):
                        message = encode_compressed(decode_frame(output), self.compress)
                    raws.append(RawMessage(topics[name], msgtype_of(message), log_time_ns,
                                           serialize(message, self.serialization),
                                           self.serialization))
            return raws
        except (ProcessorError, ReplayError, cv2.error) as err:
            text = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            raise ProcessingError(f"{self.where}: frame stamped {stamp}: {text}") from None


@dataclass
class _TopicRun:
    """One processed topic: its job, its own throttles (stateful) and its frame count."""

    job: _Job
    throttles: list[Throttle]
    read: int = 0
    undecodable: int = 0
    video: FrameStream = field(default_factory=FrameStream)  # pictures need their past

    def keep(self, stamp_ns: int) -> bool:
        """Whether every throttle passes the frame (each sees every frame)."""
        return all([throttle.keep(stamp_ns) for throttle in self.throttles])


@dataclass
class _Counts:
    read: int = 0
    processed: int = 0
    written: int = 0
    pending: deque[tuple[_TopicRun, Future[list[RawMessage] | None]]] = field(default_factory=deque)


def _check_options(processors: Sequence[Configured], topics: Sequence[str],
                   compress: str | None, thin: bool) -> None:
    if not processors:
        raise UsageError("no processor chosen")
    if not topics or len(set(topics)) != len(topics):
        raise UsageError("give each topic to process once")
    for configured in processors:
        if len(topics) > 1 and any(o.kind is OptionKind.CAMERA_INFO
                                   for o in configured.spec.options):
            raise UsageError(f"{configured.name} takes one camera's calibration: process "
                              "one topic with it per run")
    if thin and any(not c.spec.selects for c in processors):
        raise UsageError("thinning passes frames through: use only selecting processors")
    if compress is not None and compress not in COMPRESSIONS:
        raise UsageError(f"unknown compression {compress!r} (use {' or '.join(COMPRESSIONS)})")


def _record(plans: Mapping[str, list[list[tuple[str, ProcessedOutput]]]],
            processors: Sequence[Configured]) -> ProcessedOutputs:
    outputs = [o for per_topic in plans.values() for per in per_topic for _, o in per]
    options = {c.name: c.described_options() for c in processors if not c.spec.selects}
    return ProcessedOutputs(outputs, options, VERSION)


def process_log(request: ProcessRequest) -> ProcessResult:
    """Run ``processors`` over the ``topic`` list of the request's log and write its ``output``
    atomically.

    The output keeps every input message (unless ``drop_input``) plus the processors'
    outputs, which carry the input frame's log time and header; output topics are planned
    by :func:`.outputs.plan_outputs`. Selecting processors (throttle) choose the frames the
    others see; with ``thin`` (selecting processors only) the processed topics keep only
    the chosen frames, copied as stored. ``max_frames`` stops once every topic has that
    many frames (and the messages logged before them).
    """
    input_path, output, topics = request.log, request.output, list(request.topic)
    processors, output_ns, compress = request.processors, request.output_ns, request.compress
    drop_input, thin, max_frames = request.drop_input, request.thin, request.max_frames
    fmt, overwrite, workers, recover = (request.format, request.overwrite, request.workers,
                                        request.recover)
    started = time.perf_counter()
    _check_options(processors, topics, compress, thin)
    check_not_input(output, local_paths(input_path))
    computing = [c for c in processors if not c.spec.selects]
    plans = plan_outputs(topics, computing, output_ns=output_ns, compress=compress)
    record = _record(plans, processors)
    new_topics = {o.topic for o in record.outputs}
    with open_reader(input_path, recover=recover) as reader:
        require_messages(reader)
        for topic in topics:
            require_topic(reader, topic, IMAGE_TYPES if computing else STAMPED_TYPES)
        if not drop_input:
            require_free_topics(reader, new_topics, hint="leave the input topics out or "
                                "choose another output namespace")
        built = [c.build() for c in computing]
        workers = workers or min(4, os.cpu_count() or 1)
        with open_writer(output, fmt=fmt, overwrite=overwrite,
                         inputs=local_paths(input_path)) as writer:
            jobs = {topic: _TopicRun(_Job(
                tuple((proc, {name: o.topic for name, o in outs})
                      for proc, outs in zip(built, plans[topic], strict=True)),
                compress, writer.serialization, f"{reader.path}: {topic}"),
                [c.build() for c in processors if c.spec.selects]) for topic in topics}
            if computing:
                _warm_up(reader, jobs)
                writer.write(PROCESSED, record.to_message(), log_time_ns=reader.start_ns or 0)
            counts = _stream(reader, writer, jobs, workers=workers, drop_input=drop_input,
                             thin=thin, max_frames=max_frames)
    return ProcessResult(output, counts.read, counts.processed, counts.written + bool(computing),
                         time.perf_counter() - started, tuple(record.outputs),
                         {t: s.undecodable for t, s in jobs.items() if s.undecodable})


def _warm_up(reader: LogReader, jobs: Mapping[str, _TopicRun]) -> None:
    """Run the first frame of each topic: fail before writing anything, warm serializers
    (a first frame that does not decode is counted in the pass over the log)."""
    for topic, state in jobs.items():
        for first in reader.raw_messages([topic]):
            try:
                message = reader.decode(first)
            except UnsupportedEncodingError:
                raise
            except EncodingError:
                break
            if not isinstance(message, CompressedVideo):  # video: decoded in stream order
                state.job(message, first.log_time_ns)
            break


def _stream(reader: LogReader, writer: LogWriter, jobs: Mapping[str, _TopicRun], *, workers: int,
            drop_input: bool, thin: bool, max_frames: int | None) -> _Counts:
    """The copy-and-process pass over the log."""
    counts = _Counts()
    in_flight = 2 * workers + 2

    def flush(keep: int) -> None:
        while len(counts.pending) > keep:
            state, future = counts.pending.popleft()
            raws = future.result()
            if raws is None:
                state.undecodable += 1
                counts.processed -= 1
                continue
            for raw in raws:
                writer.write_raw(raw)
                counts.written += 1

    def copy(raw: RawMessage) -> None:
        if not drop_input:
            writer.write_raw(raw)
            counts.written += 1

    with ThreadPoolExecutor(workers, thread_name_prefix="camlog-process") as pool:
        try:
            for raw in reader.raw_messages():
                state = jobs.get(raw.topic)
                if state is None:
                    copy(raw)
                    continue
                if max_frames is not None and state.read >= max_frames:
                    continue  # this topic is done; others are not yet
                state.read += 1
                counts.read += 1
                try:
                    frame: Message | Frame = reader.decode(raw)
                    if isinstance(frame, CompressedVideo):
                        # on this thread, in stream order; None before the first keyframe
                        picture = state.video.decode(frame)
                        if picture is None:
                            raise EncodingError("no picture yet")
                        frame = picture
                except UnsupportedEncodingError:
                    raise
                except EncodingError:  # copied through, counted, not processed
                    state.undecodable += 1
                    copy(raw)
                    continue
                kept = state.keep(getattr(frame, "stamp_ns", raw.log_time_ns))
                if kept or not thin:
                    copy(raw)
                if kept:
                    counts.processed += 1
                    if state.job.stages:
                        counts.pending.append((state, pool.submit(state.job, frame,
                                                                  raw.log_time_ns)))
                        flush(in_flight)
                if max_frames is not None and all(s.read >= max_frames for s in jobs.values()):
                    break
            flush(0)
        except BaseException:
            for _, future in counts.pending:
                future.cancel()
            raise
    return counts
