"""A cheap first look at the logs before exporting them: the facts the layout depends on.

Reads the first message of each camera and overlay topic (its ``frame_id``, the first
camera_info) and the records of the scenario and the calibration summary. Every read
stops after one message, so the survey costs a few chunks, not a pass over the log.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

from replay.errors import ReplayError
from replay.formats.base import LogReader, RawMessage, TopicInfo
from replay.messages import CameraInfo, CompressedImage, Image
from replay.records import (
    CalibrationSummary,
    JsonRecord,
    ProcessedOutput,
    ProcessedOutputs,
    Scenario,
    outputs_by_topic,
)
from replay.topics import CALIBRATION_SUMMARY, PROCESSED, SCENARIO

from .topics import Kind, Route, classify

__all__ = ["Survey", "survey"]

R = TypeVar("R", bound=JsonRecord)

#: kinds whose first message tells which camera (frame_id) they belong to (and every
#: route that finds its camera by frame)
_FRAME_KINDS = frozenset({Kind.IMAGE, Kind.CAMERA_INFO, Kind.CALIBRATED_INFO, Kind.RECTIFIED})


@dataclass
class Survey:
    """What the layout needs to know. ``topics``: the chosen topics of every log (a topic
    in several logs is taken from the first); ``owner``: topic -> index of its log."""

    topics: dict[str, TopicInfo] = field(default_factory=dict)
    owner: dict[str, int] = field(default_factory=dict)
    routes: dict[str, Route] = field(default_factory=dict)
    frame_ids: dict[str, str] = field(default_factory=dict)  # topic -> first frame_id
    camera_infos: dict[str, CameraInfo] = field(default_factory=dict)  # topic -> first
    scenario: Scenario | None = None
    calibration_summary: CalibrationSummary | None = None
    outputs: dict[str, ProcessedOutput] = field(default_factory=dict)  # recorded outputs
    duplicates: list[str] = field(default_factory=list)  # topics left out: an earlier log has them
    image_bytes: dict[str, tuple[int, bool]] = field(default_factory=dict)  # topic -> first
    # image's bytes as stored in a recording, and whether raw (a JPEG quality shrinks it)


def _first(reader: LogReader, topic: str, start_ns: int | None, end_ns: int | None) -> Any:
    for raw in reader.raw_messages([topic], start_ns, end_ns):
        return _decoded(reader, raw)
    return None


def _decoded(reader: LogReader, raw: RawMessage) -> Any:
    try:
        return reader.decode(raw)
    except ReplayError:
        return None


def _record(message: Any, record: type[R]) -> R | None:
    """The record a message holds; None when it holds none (the layout does without)."""
    try:
        return record.from_message(message)
    except ReplayError:
        return None


def processed_outputs(readers: Sequence[LogReader]) -> dict[str, ProcessedOutput]:
    """Every output recorded on :data:`~replay.topics.PROCESSED` in any of the logs
    (whatever topics are chosen: the record is metadata); unreadable records are ignored
    (their topics are then routed by name)."""
    records = []
    for reader in readers:
        if PROCESSED not in reader.topics:
            continue
        for raw in reader.raw_messages([PROCESSED]):
            record = _record(_decoded(reader, raw), ProcessedOutputs)
            if record is not None:
                records.append(record)
    return outputs_by_topic(records)


def survey(
    readers: Sequence[LogReader],
    chosen: Sequence[list[str] | None],
    start_ns: int | None = None,
    end_ns: int | None = None,
) -> Survey:
    """Survey ``readers`` restricted to their ``chosen`` topics (None: all)."""
    result = Survey(outputs=processed_outputs(readers))
    for index, (reader, wanted) in enumerate(zip(readers, chosen, strict=True)):
        for name in sorted(reader.topics) if wanted is None else wanted:
            info = reader.topics[name]
            if info.count == 0:
                continue
            if name in result.topics:
                result.duplicates.append(f"{name} ({reader.path})")
                continue
            result.topics[name], result.owner[name] = info, index
            result.routes[name] = route = classify(name, info.msgtype, result.outputs)
            if route.kind in _FRAME_KINDS or route.by_frame:
                message = _first(reader, name, start_ns, end_ns)
                if message is None:
                    continue
                result.frame_ids[name] = getattr(message, "frame_id", "")
                if isinstance(message, Image):
                    result.image_bytes[name] = (message.pixels.nbytes, True)
                elif isinstance(message, CompressedImage):
                    result.image_bytes[name] = (len(message.data), False)
                elif isinstance(message, CameraInfo):
                    result.camera_infos[name] = message
            elif name == SCENARIO and result.scenario is None:
                result.scenario = _record(_first(reader, name, None, None), Scenario)
            elif name == CALIBRATION_SUMMARY and result.calibration_summary is None:
                result.calibration_summary = _record(_first(reader, name, None, None),
                                                     CalibrationSummary)
    return result
