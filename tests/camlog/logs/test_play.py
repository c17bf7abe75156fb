"""``play_log``: real-time pacing into a log and into an .rrd (no viewer)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from camlog.logs.play import play_log
from camlog.requests.play import PlayRequest
from replay import OptionError, open_reader
from tests.rrd import load_rrd


def raw(path: Path) -> list[tuple[str, int, bytes]]:
    with open_reader(path) as reader:
        return [(r.topic, r.log_time_ns, bytes(r.data)) for r in reader.raw_messages()]


def test_pacing_into_a_log(red_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "played.mcap"
    before_ns = time.time_ns()
    started = time.perf_counter()
    result = play_log(PlayRequest(logs=[red_log], rate=2.0, output=out, progress=False))
    wall = time.perf_counter() - started
    source = raw(red_log)
    span = (source[-1][1] - source[0][1]) / 1e9
    assert result.log_span_s == pytest.approx(span) and span > 0.6
    assert span / 2 <= wall < span / 2 + 0.4  # never early; late only by overhead
    played = raw(out)
    # every message, in order, bytes (and so header stamps) unchanged
    assert [(t, d) for t, _, d in played] == [(t, d) for t, _, d in source]
    # log time is the wall clock of emission: the log's span compressed 2x
    times = [t for _, t, _ in played]
    assert times == sorted(times) and times[0] >= before_ns
    assert (times[-1] - times[0]) / 1e9 == pytest.approx(span / 2, abs=0.1)


def test_original_log_time_and_loops(red_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "looped.bag"
    result = play_log(PlayRequest(logs=[red_log], rate=20.0, loop=2, output=out,
                                  log_time="original", topics=["/stereo_camera/left/image_raw"],
                                  progress=False))
    assert result.messages == 40 and result.loops == 2
    source = raw(red_log)
    first = [t for topic, t, _ in source if topic == "/stereo_camera/left/image_raw"]
    period = first[-1] - first[0] + (first[-1] - first[0]) // 19
    assert [t for _, t, _ in raw(out)] == first + [t + period for t in first]


def test_play_into_an_rrd(red_processed_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "played.rrd"
    started = time.perf_counter()
    result = play_log(PlayRequest(logs=[red_processed_log], rate=8.0, output=out, loop=2,
                                  progress=False))
    assert time.perf_counter() - started >= 2 * result.log_span_s / 8
    rec = load_rrd(out)
    assert rec.blueprints == 1
    image = "/world/stereo_camera/left/image"
    assert rec.count(image, "Image:buffer") == 40
    assert rec.timelines[image] == {"log_time", "header_stamp", "replay_time"}
    assert rec.count("/world/stereo_camera/left/red_pixels/mask",
                     "SegmentationImage:buffer") == 40


def test_play_needs_a_destination(red_log: Path) -> None:
    with pytest.raises(OptionError, match="choose where to play"):
        play_log(PlayRequest(logs=[red_log], progress=False))
    with pytest.raises(OptionError, match="--rate"):
        play_log(PlayRequest(logs=[red_log], rate=0, output=Path("x.mcap"), progress=False))
