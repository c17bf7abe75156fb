"""Topic patterns, time windows and the log-time merge of several logs."""

from __future__ import annotations

from pathlib import Path

import pytest

from replay import OptionError, Text, TopicError, open_reader
from replay.formats.base import TopicInfo
from replay.selection import merge_in_time, select_topics, window_ns

from .samples import write_log


def test_patterns_select_in_order_without_repeats() -> None:
    topics = {n: TopicInfo(n, "std_msgs/msg/String", 1, "cdr")
              for n in ("/cam/image_raw", "/cam/camera_info", "/imu")}
    assert select_topics(topics, None, where="x") is None
    assert select_topics(topics, ["/imu", "/cam/*", "/cam/image_raw"], where="x") == [
        "/imu", "/cam/camera_info", "/cam/image_raw"]
    with pytest.raises(TopicError, match=r"log\.mcap has no topic matching '/gps' \(topics: "):
        select_topics(topics, ["/gps"], where="log.mcap")


def test_windows() -> None:
    assert window_ns(10, None, None) == (None, None)
    assert window_ns(10, 1.0, None) == (1_000_000_010, None)
    assert window_ns(None, 1.0, 2.0) == (None, None)
    for start, end in ((2.0, 1.0), (1.0, 1.0), (-1.0, None), (None, float("nan"))):
        with pytest.raises(OptionError):
            window_ns(0, start, end)


def test_merge_keeps_log_time_order_and_ties_by_log(tmp_path: Path) -> None:
    write_log(tmp_path / "a.mcap", [("/a", t, Text(f"a{t}")) for t in (1, 3, 5)])
    write_log(tmp_path / "b.mcap", [("/b", t, Text(f"b{t}")) for t in (2, 3, 6)])
    with open_reader(tmp_path / "a.mcap") as a, open_reader(tmp_path / "b.mcap") as b:
        merged = [(r.topic, r.log_time_ns) for r in merge_in_time([a, b], [None, None])]
        windowed = [r.log_time_ns for r in merge_in_time([a, b], [None, ["/b"]], 2, 6)]
    assert merged == [("/a", 1), ("/b", 2), ("/a", 3), ("/b", 3), ("/a", 5), ("/b", 6)]
    assert windowed == [2, 3, 3, 5]
