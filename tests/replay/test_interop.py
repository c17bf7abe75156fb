"""Our logs through third-party readers: mcap_ros2, rosbags (AnyReader, McapReader), rerun."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.rosbag2.storage_mcap import McapReader
from rosbags.typesys import Stores, get_typestore

from replay import (
    IMAGE_ENCODINGS,
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
)

from .samples import Entry, every_kind, write_log


def _stamp(stamp_ns: int) -> tuple[int, int]:
    return divmod(stamp_ns, 1_000_000_000)


def expected_fields(message: Message) -> dict[str, Any]:
    """The ROS fields a message must have on the wire, built from the typed record alone."""
    match message:
        case Image():
            dtype, channels = IMAGE_ENCODINGS[message.encoding]
            return {"stamp": _stamp(message.stamp_ns), "frame_id": message.frame_id,
                    "height": message.height, "width": message.width,
                    "encoding": message.encoding, "is_bigendian": 0,
                    "step": message.width * channels * dtype.itemsize,
                    "data": message.pixels.astype("<" + dtype.str[1:]).tobytes()}
        case CompressedImage():
            return {"stamp": _stamp(message.stamp_ns), "frame_id": message.frame_id,
                    "format": message.format, "data": message.data}
        case CameraInfo():
            return {"stamp": _stamp(message.stamp_ns), "frame_id": message.frame_id,
                    "height": message.height, "width": message.width,
                    "distortion_model": message.distortion_model, "d": message.d.tolist(),
                    "k": message.k.ravel().tolist(), "r": message.r.ravel().tolist(),
                    "p": message.p.ravel().tolist(),
                    "binning": (message.binning_x, message.binning_y), "roi": message.roi}
        case PoseStamped():
            return {"stamp": _stamp(message.stamp_ns), "frame_id": message.frame_id,
                    "position": message.position_m.tolist(),
                    "orientation": message.orientation_xyzw.tolist()}
        case PointStamped():
            return {"stamp": _stamp(message.stamp_ns), "frame_id": message.frame_id,
                    "point": message.point.tolist()}
        case Text():
            return {"data": message.data}
    raise AssertionError(f"unexpected {message!r}")


def _bytes(data: Any) -> bytes:
    if isinstance(data, bytes | bytearray):
        return bytes(data)
    return np.asarray(data, np.uint8).tobytes()


def _floats(values: Any) -> list[float]:
    return [float(v) for v in values]


def actual_fields(msg: Any, msgtype: str) -> dict[str, Any]:
    """The same fields read off a third-party message object (ROS 2 or ROS1 spelling)."""
    def field(name: str) -> Any:  # ROS1 CameraInfo spells D, K, R, P
        return getattr(msg, name) if hasattr(msg, name) else getattr(msg, name.upper())

    if msgtype == "std_msgs/msg/String":
        return {"data": msg.data}
    head = {"stamp": (int(msg.header.stamp.sec), int(msg.header.stamp.nanosec)),
            "frame_id": msg.header.frame_id}
    match msgtype:
        case "sensor_msgs/msg/Image":
            return head | {"height": msg.height, "width": msg.width, "encoding": msg.encoding,
                           "is_bigendian": msg.is_bigendian, "step": msg.step,
                           "data": _bytes(msg.data)}
        case "sensor_msgs/msg/CompressedImage":
            return head | {"format": msg.format, "data": _bytes(msg.data)}
        case "sensor_msgs/msg/CameraInfo":
            roi = msg.roi
            return head | {"height": msg.height, "width": msg.width,
                           "distortion_model": msg.distortion_model,
                           "d": _floats(field("d")), "k": _floats(field("k")),
                           "r": _floats(field("r")), "p": _floats(field("p")),
                           "binning": (msg.binning_x, msg.binning_y),
                           "roi": (roi.x_offset, roi.y_offset, roi.height, roi.width,
                                   bool(roi.do_rectify))}
        case "geometry_msgs/msg/PoseStamped":
            p, q = msg.pose.position, msg.pose.orientation
            return head | {"position": [p.x, p.y, p.z], "orientation": [q.x, q.y, q.z, q.w]}
        case "geometry_msgs/msg/PointStamped":
            return head | {"point": [msg.point.x, msg.point.y, msg.point.z]}
    raise AssertionError(f"unexpected {msgtype}")


def expected_table(entries: list[Entry]) -> list[tuple[str, int, dict[str, Any]]]:
    return [(topic, log_time_ns, expected_fields(message)) for topic, log_time_ns, message
            in entries]


def test_mcap_ros2_decodes_our_mcap(tmp_path: Path) -> None:
    entries = every_kind()
    path = tmp_path / "log.mcap"
    write_log(path, entries)
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        got = [
            (channel.topic, message.log_time, actual_fields(decoded, schema.name))
            for schema, channel, message, decoded in reader.iter_decoded_messages()
        ]
        assert reader.get_header().profile == "ros2"
    assert got == expected_table(entries)


@pytest.mark.parametrize(("fmt", "name"), [("rosbag2", "bag2"), ("rosbag2-sqlite3", "bag2"),
                                           ("ros1", "log.bag")])
def test_rosbags_anyreader_reads_our_bags(tmp_path: Path, fmt: str, name: str) -> None:
    entries = every_kind()
    path = tmp_path / name
    write_log(path, entries, fmt=fmt)
    with AnyReader([path], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        got = [
            (conn.topic, log_time_ns, actual_fields(reader.deserialize(raw, conn.msgtype),
                                                    conn.msgtype))
            for conn, log_time_ns, raw in reader.messages()
        ]
    assert got == expected_table(entries)


def test_rosbags_mcap_storage_reads_our_bare_mcap(tmp_path: Path) -> None:
    entries = every_kind()
    path = tmp_path / "log.mcap"
    write_log(path, entries)
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    reader = McapReader(path)
    reader.open()
    try:
        assert reader.metadata.message_count == len(entries)
        assert sorted(conn.topic for conn in reader.connections) == sorted(t for t, _, _ in entries)
        got = [
            (conn.topic, log_time_ns,
             actual_fields(typestore.deserialize_cdr(raw, conn.msgtype), conn.msgtype))
            for conn, log_time_ns, raw in reader.messages(reader.connections)
        ]
    finally:
        reader.close()
    assert got == expected_table(entries)


def _rerun(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("rerun", path=str(Path(sys.executable).parent)) or "rerun"
    # keep rerun's first-run config and analytics state out of the user's home
    env = os.environ | {f"XDG_{kind}_HOME": str(cwd / "xdg") for kind in ("CONFIG", "DATA",
                                                                           "CACHE")}
    return subprocess.run([exe, *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=120, check=False)


@pytest.mark.slow
def test_rerun_converts_our_mcap(tmp_path: Path) -> None:
    write_log(tmp_path / "log.mcap", every_kind())
    convert = _rerun("mcap", "convert", "log.mcap", "-o", "log.rrd", cwd=tmp_path)
    assert convert.returncode == 0, convert.stderr
    rrd = tmp_path / "log.rrd"
    assert rrd.stat().st_size > 0
    verify = _rerun("rrd", "verify", "log.rrd", cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr
    printed = _rerun("rrd", "print", "log.rrd", cwd=tmp_path)
    assert printed.returncode == 0, printed.stderr
    columns = {line.split(" - ")[1]: line for line in printed.stdout.splitlines()
               if line.startswith("Chunk(") and " - /" in line}
    assert "Image:buffer" in columns["/cam/rgb8"]
    assert "EncodedImage:blob" in columns["/cam/compressed"]
    assert "Pinhole:image_from_camera" in columns["/cam/camera_info"]
