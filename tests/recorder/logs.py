"""Reading recorded logs back for the recorder tests."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from recorder.record import RecordResult, record
from recorder.scenario import load_scenario
from replay import CameraInfo, Image, Message, PoseStamped, Text, open_reader
from replay.geometry import rotation_from_quat_xyzw
from replay.messages import F64

SCENARIO_TOPIC = "/camlog/scenario"


@dataclass
class Log:
    """A recording and every message in it, decoded, per topic in log-time order."""

    path: Path
    result: RecordResult
    topics: dict[str, list[Message]]
    counts: dict[str, int]  # topic -> count the reader's index reports

    def images(self, namespace: str) -> list[Image]:
        return [m for m in self.topics[f"{namespace}/image_raw"] if isinstance(m, Image)]

    def infos(self, namespace: str) -> list[CameraInfo]:
        return [m for m in self.topics[f"{namespace}/camera_info"] if isinstance(m, CameraInfo)]

    def truths(self, namespace: str, target: str) -> list[PoseStamped]:
        topic = f"{namespace}/ground_truth/{target}"
        return [m for m in self.topics[topic] if isinstance(m, PoseStamped)]

    @property
    def scenario(self) -> dict[str, Any]:
        (text,) = self.topics[SCENARIO_TOPIC]
        assert isinstance(text, Text)
        data: dict[str, Any] = json.loads(text.data)
        return data

    def camera(self, name: str) -> dict[str, Any]:
        (entry,) = (c for c in self.scenario["cameras"] if c["name"] == name)
        return entry


def read_log(path: Path, result: RecordResult) -> Log:
    topics: dict[str, list[Message]] = {}
    with open_reader(path) as reader:
        counts = {name: info.count for name, info in reader.topics.items()}
        for rec in reader.messages():
            topics.setdefault(rec.topic, []).append(rec.message)
    return Log(path, result, topics, counts)


def record_log(
    scenario: str | Path, path: Path, *, fmt: str | None = None, **overrides: Any
) -> Log:
    """Record ``scenario`` with ``overrides`` to ``path`` and read it back."""
    result = record(load_scenario(str(scenario), overrides), path, fmt=fmt, progress=False)
    return read_log(path, result)


def transform(pose: PoseStamped) -> F64:
    """``frame_id_from_child`` (4, 4) of a pose message."""
    out = np.eye(4)
    out[:3, :3] = rotation_from_quat_xyzw(pose.orientation_xyzw)
    out[:3, 3] = pose.position_m
    return out


def translation(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> F64:
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out
