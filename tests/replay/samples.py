"""Sample messages and output names shared by the log-layer tests."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from replay import (
    IMAGE_ENCODINGS,
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
    open_reader,
    open_writer,
)
from replay.frames import decode_frame, encode_compressed
from replay.frames.raw import RAW_ENCODINGS

#: writer format name -> output name it is written under
OUTPUT_NAMES = {
    "mcap": "log.mcap",
    "rosbag2": "log",
    "rosbag2-sqlite3": "log",
    "ros1": "log.bag",
}
WRITE_FORMATS = tuple(OUTPUT_NAMES)
#: the encodings every writer must carry losslessly
ROUND_TRIP_ENCODINGS = ("rgb8", "bgr8", "rgba8", "bgra8", "mono8", "mono16", "16UC1")
T0_NS = 1_700_000_000_123_456_789

#: (topic, log_time_ns, message)
Entry = tuple[str, int, Message]


def random_pixels(encoding: str, *, height: int = 6, width: int = 8, seed: int = 0) -> np.ndarray:
    """Pixels over the full value range of ``encoding``: ``(H, W)`` or ``(H, W, C)``
    (semi-planar YUV: its buffer's rows, e.g. ``(H * 3 / 2, W)`` for nv21)."""
    dtype, channels = IMAGE_ENCODINGS[encoding]
    rows = int(height * RAW_ENCODINGS[encoding].rows)
    shape = (rows, width) if channels == 1 else (rows, width, channels)
    rng = np.random.default_rng(seed)
    if dtype.kind == "f":
        return rng.uniform(0.0, 10.0, size=shape).astype(dtype)
    info = np.iinfo(dtype)
    return rng.integers(info.min, info.max, size=shape, dtype=dtype, endpoint=True)


def every_kind() -> list[Entry]:
    """One message of every kind camlog writes, log times strictly increasing from T0_NS.

    Log times equal header stamps (Text has none and is logged last).
    """
    messages: list[tuple[str, Message]] = []
    for index, encoding in enumerate(ROUND_TRIP_ENCODINGS):
        pixels = random_pixels(encoding, seed=index)
        messages.append((f"/cam/{encoding}", Image(T0_NS + index, "cam_optical", encoding, pixels)))
    rgb = Image(T0_NS, "cam_optical", "rgb8", random_pixels("rgb8"))
    jpeg = encode_compressed(decode_frame(rgb))
    messages += [
        ("/cam/compressed", CompressedImage(T0_NS + 10, "cam_optical", jpeg.format, jpeg.data)),
        (
            "/cam/camera_info",
            CameraInfo(
                stamp_ns=T0_NS + 11,
                frame_id="cam_optical",
                width=640,
                height=480,
                distortion_model="plumb_bob",
                d=np.array([-0.25, 0.07, 1e-4, -2e-4, 0.0]),
                k=np.array([[500.5, 0.0, 320.25], [0.0, 501.0, 240.75], [0.0, 0.0, 1.0]]),
                r=np.eye(3),
                p=np.array([[500.5, 0, 320.25, -35.0], [0, 501.0, 240.75, 0], [0, 0, 1, 0]]),
                binning_x=1,
                binning_y=2,
                roi=(4, 8, 100, 200, True),
            ),
        ),
        (
            "/rig/pose",
            PoseStamped(T0_NS + 12, "world", np.array([1.0, -2.5, 0.125]),
                        np.array([0.0, 0.0, 0.6, 0.8])),
        ),
        ("/rig/point", PointStamped(T0_NS + 13, "world", np.array([0.5, 1e-9, -3.0]))),
    ]
    entries = [(topic, getattr(message, "stamp_ns", 0), message) for topic, message in messages]
    entries.append(("/scenario", T0_NS + 14, Text("name: desk\nseed: 7  # ünïcode")))
    return entries


def write_log(path: Path, entries: Iterable[Entry], *, fmt: str | None = None,
              **options: Any) -> None:
    """Write ``(topic, log_time_ns, message)`` entries with :func:`replay.open_writer`."""
    with open_writer(path, fmt=fmt, **options) as writer:
        for topic, log_time_ns, message in entries:
            writer.write(topic, message, log_time_ns=log_time_ns)


def read_log(path: Path, **filters: Any) -> list[Entry]:
    """All decoded ``(topic, log_time_ns, message)`` entries of a log, in reading order."""
    with open_reader(path) as reader:
        return [(r.topic, r.log_time_ns, r.message) for r in reader.messages(**filters)]
