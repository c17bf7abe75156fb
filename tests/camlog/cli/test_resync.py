"""``camlog resync`` on a recorded unsynchronised rig, against the recorder's dropped frames."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from replay import CameraInfo, Image, PointStamped, Text, open_reader
from tests.outputs import temp_outputs
from tests.slow import renders

SCENARIOS = Path(__file__).resolve().parents[3] / "datasets" / "scenarios"
FRAMES = 90


@pytest.fixture(scope="module")
@renders
def unsynced(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """stereo_unsynced with many drops and 0.5 ms jitter.

    The right camera runs 7 ms behind the left at 30 Hz, so a frame's true partner is
    7 ms away and the neighbouring one 26 ms away, on either side of the 16.7 ms default
    slop. 0.5 ms jitter keeps both many sigma from the slop, so the drops can be checked
    exactly.
    """
    tmp = tmp_path_factory.mktemp("unsynced")
    text = (SCENARIOS / "stereo_unsynced.toml").read_text()
    assert text.count("jitter_s = 0.0015") == 2 and text.count("drop_probability = 0.015") == 2
    spec = tmp / "drops.toml"
    spec.write_text(text.replace("jitter_s = 0.0015", "jitter_s = 0.0005")
                    .replace("drop_probability = 0.015", "drop_probability = 0.12"))
    log = tmp / "unsynced.mcap"
    assert main(["record", str(spec), "-o", str(log), "--frames", str(FRAMES),
                 "--resolution", "320x240", "--no-progress"]) == 0
    return log


@pytest.fixture(scope="module")
def synced(unsynced: Path) -> Path:
    out = unsynced.with_name("synced.mcap")
    assert main(["resync", str(unsynced), "-o", str(out)]) == 0
    return out


def by_topic(path: Path) -> dict[str, list[object]]:
    out: dict[str, list[object]] = {}
    with open_reader(path) as reader:
        for rec in reader.messages():
            out.setdefault(rec.topic, []).append(rec.message)
    return out


def stamps(messages: list[object]) -> list[int]:
    return [m.stamp_ns for m in messages if isinstance(m, Image | CameraInfo | PointStamped)]


class Truth:
    """What the recorder says: dropped frame indices, and the frame index of a stamp."""

    def __init__(self, src: dict[str, list[object]]) -> None:
        scenario = src["/camlog/scenario"][0]
        assert isinstance(scenario, Text)
        spec = json.loads(scenario.data)
        self.dropped = {c["name"]: set(c["dropped_frames"]) for c in spec["cameras"]}
        self.phase_ns = {c["name"]: c.get("phase_s", 0.0) * 1e9 for c in spec["spec"]["cameras"]}
        self.period_ns = 1e9 / spec["spec"]["rate_hz"]
        self.start_ns = min(stamps(src["/unsynced/left/image_raw"]))  # frame 0 is never dropped

    def frame(self, side: str, stamp_ns: int) -> int:
        return round((stamp_ns - self.start_ns - self.phase_ns[side]) / self.period_ns)


def test_pairs_every_frame_with_its_partner_once(unsynced: Path, synced: Path) -> None:
    src, out = by_topic(unsynced), by_topic(synced)
    truth = Truth(src)
    dropped = truth.dropped
    assert dropped["left"] - dropped["right"] and dropped["right"] - dropped["left"]
    left_in = stamps(src["/unsynced/left/image_raw"])
    right_in = stamps(src["/unsynced/right/image_raw"])
    assert [truth.frame("left", s) for s in left_in] == sorted(
        set(range(FRAMES)) - dropped["left"])

    # identical stamps on both sides, for images and camera_info alike
    left_out, right_out = (stamps(out[f"/stereo_sync/{s}/image_raw"]) for s in ("left", "right"))
    assert left_out == right_out == stamps(out["/stereo_sync/left/camera_info"]) == stamps(
        out["/stereo_sync/right/camera_info"])
    assert np.all(np.diff(left_out) > 0)

    # recover each pair's input stamps from the common (later) stamp and the offset
    offsets = out["/stereo_sync/offset_s"]
    assert stamps(offsets) == left_out
    inputs = []
    for common, offset in zip(left_out, offsets, strict=True):
        assert isinstance(offset, PointStamped)
        offset_ns = round(offset.point[0] * 1e9)
        left, right = (common - offset_ns, common) if offset_ns >= 0 else (
            common, common + offset_ns)
        assert left in left_in and right in right_in
        inputs.append((left, right))
    pairs = [(truth.frame("left", a), truth.frame("right", b)) for a, b in inputs]
    lefts, rights = zip(*pairs, strict=True)
    assert len(set(lefts)) == len(lefts) and len(set(rights)) == len(rights)  # used once
    both = sorted(set(range(FRAMES)) - dropped["left"] - dropped["right"])
    assert pairs == [(i, i) for i in both]  # every frame whose partner exists, correctly

    # the pixels are the inputs', re-stamped
    originals = {m.stamp_ns: m for m in src["/unsynced/right/image_raw"] if isinstance(m, Image)}
    for image, (_, right) in zip(out["/stereo_sync/right/image_raw"], inputs, strict=True):
        assert isinstance(image, Image)
        assert np.array_equal(image.pixels, originals[right].pixels)


def test_reports_the_dropped_frames_exactly(unsynced: Path, synced: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    src, out = by_topic(unsynced), by_topic(synced)
    truth = Truth(src)
    dropped = truth.dropped
    stats_text = out["/stereo_sync/stats"][0]
    assert isinstance(stats_text, Text)
    stats = json.loads(stats_text.data)

    def frames(side: str) -> list[int]:
        return [truth.frame(side, s) for s in stats[f"{side}_unpaired_stamps_ns"]]

    assert frames("left") == sorted(dropped["right"] - dropped["left"])
    assert frames("right") == sorted(dropped["left"] - dropped["right"])
    assert stats["pairs"] == FRAMES - len(dropped["left"] | dropped["right"])
    assert stats["left_frames"] == FRAMES - len(dropped["left"])
    offset = stats["offset_right_minus_left_ns"]
    assert 4e6 < offset["min"] <= offset["median"] <= offset["max"] < 10e6  # 7 ms phase
    assert stats["slop_ns"] == pytest.approx(truth.period_ns / 2, abs=2e5)
    assert stats["peak_buffered_messages"] <= 8  # bounded look-ahead, not the log length

    # the command prints the same numbers
    out_path = synced.with_name("again.mcap")
    assert main(["resync", str(unsynced), "-o", str(out_path)]) == 0
    printed = capsys.readouterr().out
    assert f"paired {stats['pairs']} of {stats['left_frames']} left" in printed
    assert f"unpaired left: {len(frames('left'))} [" in printed


def test_keeps_every_input_topic(unsynced: Path, synced: Path) -> None:
    with open_reader(unsynced) as src, open_reader(synced) as out:
        for topic, info in src.topics.items():
            assert out.topics[topic].count == info.count
        added = set(out.topics) - set(src.topics)
        assert added == {f"/stereo_sync/{s}/{t}" for s in ("left", "right")
                         for t in ("image_raw", "camera_info")} | {
            "/stereo_sync/offset_s", "/stereo_sync/stats"}


def test_explicit_slop_and_prefix(unsynced: Path, tmp_path: Path) -> None:
    out = tmp_path / "wide.mcap"
    assert main(["resync", str(unsynced), "-o", str(out), "--slop", "0.02",
                 "--out-prefix", "/pair"]) == 0
    with open_reader(out) as reader:
        assert "/pair/left/image_raw" in reader.topics
        stats = json.loads(next(r.message for r in reader.messages(["/pair/stats"])).data)
    assert stats["slop_ns"] == 20_000_000 and stats["slop_source"] == "given"


def test_no_partner_within_slop(unsynced: Path, tmp_path: Path,
                                capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "none.mcap"
    assert main(["resync", str(unsynced), "-o", str(out), "--slop", "0.001"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("camlog resync: error: ")
    assert "no /unsynced/left/image_raw frame has a /unsynced/right/image_raw partner" in err
    assert not out.exists() and temp_outputs(tmp_path) == []


def test_missing_camera_lists_the_topics(unsynced: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x.mcap"
    assert main(["resync", str(unsynced), "-o", str(out), "--left", "/cam0"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "/cam0/image_raw" in err
    assert "/unsynced/left/image_raw" in err
    assert not out.exists()


def test_compressed_cameras_without_camera_info(tmp_path: Path) -> None:
    from replay import CompressedImage, open_writer
    from replay.frames import decode_frame, encode_compressed

    ms = 1_000_000
    log = tmp_path / "compressed.mcap"
    left_ms, right_ms = [0, 33, 33, 66], [10, 43, 76]
    with open_writer(log) as writer:
        for side, times in (("a", left_ms), ("b", right_ms)):
            for i, t in enumerate(times):
                pixels = np.full((8, 8), 10 * i + (side == "b"), np.uint8)
                frame = decode_frame(Image(t * ms, side, "mono8", pixels))
                writer.write(f"/{side}/image_raw/compressed", encode_compressed(frame, "png"))
    out = tmp_path / "out.mcap"
    assert main(["resync", str(log), "-o", str(out), "--left", "/a", "--right", "/b/"]) == 0
    got = by_topic(out)
    assert "/stereo_sync/left/camera_info" not in got
    stats_text = got["/stereo_sync/stats"][0]
    assert isinstance(stats_text, Text)
    stats = json.loads(stats_text.data)
    assert stats["pairs"] == 3 and stats["left_unpaired_stamps_ns"] == [33 * ms]
    for side, values in (("left", [0, 10, 30]), ("right", [1, 11, 21])):
        images = got[f"/stereo_sync/{side}/image_raw/compressed"]
        assert [m.stamp_ns for m in images if isinstance(m, CompressedImage)] == [
            10 * ms, 43 * ms, 76 * ms]
        # of the two left frames stamped 33 ms the first one (value 10) is paired
        assert [int(decode_frame(m).pixels[0, 0]) for m in images
                if isinstance(m, CompressedImage)] == values


def test_video_cameras_resync_like_raw_ones(unsynced: Path, synced: Path, tmp_path: Path
                                            ) -> None:
    """Both cameras as foxglove.CompressedVideo H.264 (``convert --compress h264``): the same
    pairs as the raw log's, and the paired pictures as a video stream of their own that
    PyAV alone decodes, picture for picture, to the raw pairs' images."""
    import av

    from replay import CompressedVideo
    from replay.frames import psnr_db

    video = tmp_path / "video.mcap"
    assert main(["convert", str(unsynced), str(video), "--compress", "h264",
                 "--no-progress"]) == 0
    out = tmp_path / "synced_video.mcap"
    assert main(["resync", str(video), "-o", str(out)]) == 0
    raw, got = by_topic(synced), by_topic(out)
    raw_stats, got_stats = (json.loads(t.data) for t in (raw["/stereo_sync/stats"][0],
                                                          got["/stereo_sync/stats"][0])
                            if isinstance(t, Text))
    assert got_stats["pairs"] == raw_stats["pairs"] > 0
    for side in ("left", "right"):
        images = [m for m in raw[f"/stereo_sync/{side}/image_raw"] if isinstance(m, Image)]
        samples = [m for m in got[f"/stereo_sync/{side}/image_raw/video"]
                   if isinstance(m, CompressedVideo)]
        assert [m.stamp_ns for m in samples] == [m.stamp_ns for m in images]
        assert stamps(got[f"/stereo_sync/{side}/camera_info"]) == \
            stamps(raw[f"/stereo_sync/{side}/camera_info"])
        codec = av.CodecContext.create("h264", "r")
        for sample, image in zip(samples, images, strict=True):
            (picture,) = codec.decode(av.Packet(sample.data))
            # two generations of lossy coding (convert, then resync)
            assert psnr_db(image.pixels, picture.to_ndarray(format="rgb24")) > 28.0
    assert [p.stamp_ns for p in got["/stereo_sync/offset_s"] if isinstance(p, PointStamped)] \
        == [p.stamp_ns for p in raw["/stereo_sync/offset_s"] if isinstance(p, PointStamped)]
