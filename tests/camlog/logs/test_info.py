"""``camlog.logs.info``: per-topic counts, rates and stream descriptions, and their text."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

import numpy as np
import pytest

from camlog.logs import info
from camlog.logs.info import (
    FIRST_MESSAGES_WINDOW_NS,
    FrameCheck,
    LogSummary,
    TopicSummary,
    first_messages,
    format_size,
    format_stamp,
    format_summary,
    size_on_disk,
    summarize,
)
from replay import (
    CameraInfo,
    Image,
    LogReader,
    Message,
    PoseStamped,
    RawMessage,
    Text,
    open_reader,
    open_writer,
)
from replay.frames import decode_frame, encode_compressed
from replay.wire import CDR, ros2_typestore
from tests.replay.samples import T0_NS, WRITE_FORMATS, Entry, random_pixels, write_log

PERIOD_NS = 100_000_000  # 10 Hz


def camera_entries(frames: int = 5) -> list[Entry]:
    """A 10 Hz camera (raw, compressed, info), a 20 Hz pose and one text message."""
    entries: list[Entry] = []
    for i in range(frames):
        stamp_ns = T0_NS + i * PERIOD_NS
        image = Image(stamp_ns, "cam", "bgr8", random_pixels("bgr8", height=48, width=64, seed=i))
        info = CameraInfo(stamp_ns, "cam", 64, 48, "rational_polynomial", np.zeros(8), np.eye(3))
        entries += [
            ("/cam/image_raw", stamp_ns, image),
            ("/cam/image_raw/compressed", stamp_ns, encode_compressed(decode_frame(image), "png")),
            ("/cam/camera_info", stamp_ns, info),
        ]
    for i in range(2 * frames - 1):
        stamp_ns = T0_NS + i * PERIOD_NS // 2
        pose: Message = PoseStamped(stamp_ns, "world", [i, 0, 0], [0, 0, 0, 1])
        entries.append(("/rig/pose", stamp_ns, pose))
    entries.append(("/notes", T0_NS + 7, Text("hello")))
    return entries


@pytest.mark.parametrize("verify", [False, True], ids=["index", "verify"])
@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_summary_of_every_format(fmt: str, verify: bool,
                                 log_path: Callable[[str], Path]) -> None:
    path = log_path(fmt)
    write_log(path, camera_entries(), fmt=fmt)
    with open_reader(path) as reader:
        summary = summarize(reader, verify=verify)
        assert summary.format_name == reader.format_name
    assert summary.path == path
    assert summary.size_bytes == size_on_disk(path) > 0
    assert summary.message_count == 5 * 3 + 9 + 1
    assert summary.start_ns == T0_NS
    assert summary.end_ns == T0_NS + 4 * PERIOD_NS
    assert summary.duration_s == pytest.approx(0.4)
    assert summary.warnings == ()
    topics = {topic.name: topic for topic in summary.topics}
    assert [topic.name for topic in summary.topics] == sorted(topics)
    assert {name: (t.msgtype, t.count, t.detail) for name, t in topics.items()} == {
        "/cam/image_raw": ("sensor_msgs/msg/Image", 5, "bgr8 64x48"),
        "/cam/image_raw/compressed": ("sensor_msgs/msg/CompressedImage", 5,
                                      "bgr8; png compressed bgr8 64x48"),
        "/cam/camera_info": ("sensor_msgs/msg/CameraInfo", 5, "64x48 rational_polynomial"),
        "/rig/pose": ("geometry_msgs/msg/PoseStamped", 9, ""),
        "/notes": ("std_msgs/msg/String", 1, ""),
    }
    assert topics["/cam/image_raw"].rate_hz == pytest.approx(10.0)
    assert topics["/rig/pose"].rate_hz == pytest.approx(20.0)
    assert topics["/notes"].rate_hz is None


def test_index_spans_equal_the_streamed_ones_over_many_chunks(tmp_path: Path) -> None:
    # small chunks interleave the topics over many chunks, out of order across them
    path = tmp_path / "many_chunks.mcap"
    entries = camera_entries(frames=12)
    write_log(path, entries[::2] + entries[1::2], chunk_size=2_000)
    with open_reader(path) as reader:
        assert reader.topic_spans() is not None
        indexed, streamed = summarize(reader), summarize(reader, verify=True)
    assert streamed.frames == FrameCheck(12 * 2, {})  # verify decodes every frame
    assert indexed == dataclasses.replace(streamed, frames=None)
    assert {t.name: (t.first_ns, t.last_ns) for t in indexed.topics}["/rig/pose"] == (
        T0_NS, T0_NS + 22 * PERIOD_NS // 2)


def test_only_the_first_image_of_a_topic_is_decoded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "log.mcap"
    write_log(path, camera_entries(frames=6))
    decoded: list[str] = []
    real_decode, real_by_schema = LogReader.decode, info._describe_by_schema

    def counting(self: LogReader, raw: RawMessage) -> Message:
        decoded.append(raw.msgtype)
        return real_decode(self, raw)

    def counting_by_schema(raw: RawMessage) -> str | None:
        described = real_by_schema(raw)
        if described is not None:  # described without the reader's decode
            decoded.append(raw.msgtype)
        return described

    monkeypatch.setattr(LogReader, "decode", counting)
    monkeypatch.setattr(info, "_describe_by_schema", counting_by_schema)
    with open_reader(path) as reader:
        summary = summarize(reader)
    assert sorted(decoded) == ["sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/CompressedImage",
                               "sensor_msgs/msg/Image"]
    assert summary.message_count == 6 * 3 + 11 + 1


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_first_messages_of_topics_that_begin_together_are_read_in_one_pass(
    fmt: str, log_path: Callable[[str], Path]
) -> None:
    late_ns = T0_NS + 3 * FIRST_MESSAGES_WINDOW_NS  # a camera switched on later
    entries = camera_entries(frames=4) + [
        ("/late/image_raw", late_ns + i, Image(late_ns + i, "late", "mono8",
                                               random_pixels("mono8", height=8, width=8, seed=i)))
        for i in range(2)]
    path = log_path(fmt)
    write_log(path, entries, fmt=fmt)
    first_ns = {"/cam/camera_info": T0_NS, "/cam/image_raw": T0_NS, "/late/image_raw": late_ns,
                "/rig/pose": T0_NS}
    with open_reader(path) as reader:
        passes: list[list[str]] = []
        read = reader.raw_messages

        def counting(topics: Iterable[str] | None = None, start_ns: int | None = None,
                     end_ns: int | None = None) -> Iterator[RawMessage]:
            passes.append(sorted(topics or ()))
            return read(topics, start_ns, end_ns)

        reader.raw_messages = counting  # type: ignore[method-assign]
        found = {raw.topic: raw.log_time_ns for raw in first_messages(reader, first_ns)}
    assert found == first_ns
    assert passes == [["/cam/camera_info", "/cam/image_raw", "/rig/pose"], ["/late/image_raw"]]


def test_undecodable_image_is_described_not_fatal(tmp_path: Path) -> None:
    types = ros2_typestore().types
    msg = types["sensor_msgs/msg/Image"](
        header=types["std_msgs/msg/Header"](
            stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="cam"
        ),
        height=2, width=2, encoding="yuv411", is_bigendian=0, step=4,
        data=np.zeros(8, np.uint8),
    )
    data = bytes(ros2_typestore().serialize_cdr(msg, "sensor_msgs/msg/Image"))
    path = tmp_path / "yuv.mcap"
    with open_writer(path) as writer:
        for i in range(3):
            writer.write_raw(RawMessage("/cam/yuv", "sensor_msgs/msg/Image", i * 50_000_000, data,
                                        CDR))
    with open_reader(path) as reader:
        (topic,) = summarize(reader).topics
    assert topic.count == 3
    assert topic.rate_hz == pytest.approx(20.0)
    assert topic.detail.startswith("(cannot decode:")
    assert "'yuv411'" in topic.detail


def test_truncated_log_summary_carries_the_warning(tmp_path: Path) -> None:
    path = tmp_path / "full.mcap"
    entries = [("/cam/image_raw", T0_NS + i, Image(T0_NS + i, "cam", "mono8",
                                                      random_pixels("mono8", height=64, width=64,
                                                                    seed=i)))
               for i in range(30)]
    write_log(path, entries, chunk_size=10_000)
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with open_reader(cut) as reader:
        summary = summarize(reader)
    assert 0 < summary.message_count < 30
    assert summary.size_bytes == cut.stat().st_size
    assert len(summary.warnings) == 1
    text = format_summary(summary)
    assert text.splitlines()[-1] == f"warning: {summary.warnings[0]}"
    assert "incomplete" in text.splitlines()[-1]


def test_empty_log(tmp_path: Path) -> None:
    path = tmp_path / "empty.mcap"
    with open_writer(path):
        pass
    with open_reader(path) as reader:
        summary = summarize(reader)
    assert (summary.message_count, summary.start_ns, summary.end_ns) == (0, None, None)
    assert summary.duration_s == 0.0
    assert "start:     -" in format_summary(summary)


def test_rate_needs_two_distinct_times() -> None:
    assert TopicSummary("/a", "t", 1, 5, 5).rate_hz is None
    assert TopicSummary("/a", "t", 3, 5, 5).rate_hz is None
    assert TopicSummary("/a", "t", 0, None, None).rate_hz is None
    assert TopicSummary("/a", "t", 3, 0, 500_000_000).rate_hz == pytest.approx(4.0)


def test_format_helpers() -> None:
    assert format_stamp(None) == "-"
    assert format_stamp(1_553_180_224_368_061_647) == (
        "2019-03-21T14:57:04.368061647Z (1553180224368061647 ns)"
    )
    assert format_stamp(5) == "1970-01-01T00:00:00.000000005Z (5 ns)"
    assert format_size(512) == "512 B (512 bytes)"
    assert format_size(4_129_654) == "3.9 MiB (4129654 bytes)"


def test_size_on_disk_sums_directories(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "a").write_bytes(b"x" * 10)
    (tmp_path / "sub" / "b").write_bytes(b"y" * 5)
    assert size_on_disk(tmp_path) == 15
    assert size_on_disk(tmp_path / "a") == 10


def test_format_summary_text() -> None:
    summary = LogSummary(
        path=Path("/logs/run.mcap"),
        format_name="mcap",
        size_bytes=2048,
        start_ns=1_000_000_000,
        end_ns=3_500_000_000,
        message_count=8,
        topics=(
            TopicSummary("/cam/image_raw", "sensor_msgs/msg/Image", 6, 1_000_000_000,
                         3_500_000_000, "mono8 848x800"),
            TopicSummary("/notes", "std_msgs/msg/String", 2, 2_000_000_000, 2_000_000_000),
        ),
        warnings=("/logs/run.mcap is incomplete (cut)",),
    )
    assert format_summary(summary) == "\n".join([
        "path:      /logs/run.mcap",
        "format:    mcap",
        "size:      2.0 KiB (2048 bytes)",
        "start:     1970-01-01T00:00:01.000000000Z (1000000000 ns)",
        "end:       1970-01-01T00:00:03.500000000Z (3500000000 ns)",
        "duration:  2.500 s",
        "messages:  8",
        "topics:    2",
        "frames:    not decoded (--verify decodes every one)",
        "  topic           type                   count  rate_hz  detail",
        "  /cam/image_raw  sensor_msgs/msg/Image      6     2.00  mono8 848x800",
        "  /notes          std_msgs/msg/String        2",
        "warning: /logs/run.mcap is incomplete (cut)",
    ])
