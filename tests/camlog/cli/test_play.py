"""``camlog play`` through the command line (no viewer: into a log and into an .rrd)."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import pytest
from rerun.error_utils import RerunWarning
from rosbags.highlevel import AnyReader

from camlog.cli import main
from tests.recordings import RED_FRAMES
from tests.rrd import Receiver, load_rrd, rerun_cli


@pytest.mark.slow
def test_play_into_a_log_at_a_high_rate(red_log: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "played.mcap"
    started = time.perf_counter()
    assert main(["play", str(red_log), "--rate", "4", "-o", str(out), "--no-progress"]) == 0
    wall = time.perf_counter() - started
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("played 121 messages (1 loop(s) of 0.633 s at 4x)")
    assert 0.633 / 4 <= wall < 0.633 / 4 + 1.0
    with AnyReader([out]) as reader:
        assert sum(1 for _ in reader.messages()) == 121
    converted = rerun_cli("mcap", "convert", str(out), "-o", "played.rrd", cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr


def test_play_errors(red_log: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["play", str(red_log)]) == 1
    assert "choose where to play to" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["play", str(red_log), "--rate", "0", "-o", "x.mcap"])
    assert "--rate: expected a number >= 0.001" in capsys.readouterr().err


def test_play_to_a_live_viewer(red_log: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    """``--connect`` streams to a running rerun (here a headless one that saves to disk)."""
    receiver = Receiver(tmp_path)
    try:
        assert main(["play", str(red_log), "--rate", "8", "--connect", receiver.url,
                     "--no-progress"]) == 0
        assert capsys.readouterr().out.startswith("played 121 messages")
        images = 0
        deadline = time.monotonic() + 20
        while images < 20 and time.monotonic() < deadline:  # the receiver writes as it goes
            time.sleep(0.2)
            with warnings.catch_warnings():  # the file has no footer while it is written
                warnings.filterwarnings("ignore", "RRD file has no footer", RerunWarning)
                try:
                    rec = load_rrd(receiver.path)
                except (OSError, ValueError):
                    continue
            images = rec.count("/world/stereo_camera/left/image", "Image:buffer")
    finally:
        receiver.stop()
    assert images == 20
    assert rec.timelines["/world/stereo_camera/left/image"] == {"log_time", "header_stamp",
                                                                "replay_time"}
    assert rec.blueprints == 1


def test_play_video_topics(red_log: Path, tmp_path: Path,
                           capsys: pytest.CaptureFixture[str]) -> None:
    """Both cameras as foxglove.CompressedVideo H.264: replayed into an .rrd as rerun video
    samples (every picture), and into a log whose samples PyAV alone decodes."""
    import av
    from mcap.reader import make_reader

    video = tmp_path / "video.mcap"
    assert main(["convert", str(red_log), str(video), "--compress", "h264", "--no-progress"]) == 0
    rrd = tmp_path / "played.rrd"
    assert main(["play", str(video), "--rate", "8", "-o", str(rrd), "--no-progress"]) == 0
    rec = load_rrd(rrd)
    for side in ("left", "right"):
        assert rec.count(f"/world/stereo_camera/{side}/video", "VideoStream:sample") == \
            RED_FRAMES
    assert "replay_time" in rec.timelines["/world/stereo_camera/left/video"]
    played = tmp_path / "played.mcap"
    assert main(["play", str(video), "--rate", "8", "-o", str(played), "--no-progress"]) == 0
    capsys.readouterr()
    from foxglove_schemas_protobuf.CompressedVideo_pb2 import CompressedVideo

    codec = av.CodecContext.create("h264", "r")
    pictures = 0
    with played.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(
                topics=["/stereo_camera/left/image_raw/video"]):
            assert channel.message_encoding == "protobuf"
            sample = CompressedVideo.FromString(message.data)
            (picture,) = codec.decode(av.Packet(sample.data))
            assert picture.to_ndarray(format="rgb24").shape == (240, 320, 3)
            pictures += 1
    assert pictures == RED_FRAMES
