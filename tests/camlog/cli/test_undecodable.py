"""Frames that do not decode (a JPEG cut short, a raw buffer too small for its size, video
pictures before the first keyframe), made with OpenCV, the mcap libraries and PyAV:
``process`` copies them through, ``convert`` leaves them out, ``view`` does not show them and
``info --verify`` finds them; each counts them and says so once per topic."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from foxglove_schemas_protobuf.CompressedVideo_pb2 import CompressedVideo
from google.protobuf.timestamp_pb2 import Timestamp
from mcap.reader import make_reader
from mcap_protobuf.writer import Writer as ProtobufWriter
from mcap_ros2.writer import Writer as Ros2Writer

from camlog.cli import main
from replay import CompressedImage, Image, PointStamped, open_reader, open_writer
from replay.wire import ros2_typestore
from tests.conftest import REPO_ROOT
from tests.encodings import HEIGHT, RED_CENTROID, WIDTH, scene_rgb
from tests.rrd import load_rrd

T0_NS = 3_000_000_000
PERIOD_NS = 50_000_000
FRAMES = 6
BAD_JPEG = {1, 4}  # frames whose JPEG is cut in half
BAD_RAW = {2}  # frames whose raw buffer lacks its last row
GOP, DROPPED = 4, 1  # the video's first packet (its keyframe) is left out


def _header(t: int, frame_id: str) -> dict[str, object]:
    return {"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "frame_id": frame_id}


def _ros_log(path: Path) -> Path:
    """A JPEG topic and an rgb8 topic with the bad frames above, written with mcap_ros2."""
    store = ros2_typestore()
    rgb = scene_rgb()
    ok, jpeg = cv2.imencode(".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    assert ok
    with path.open("wb") as f:
        writer = Ros2Writer(f)
        image = writer.register_msgdef("sensor_msgs/msg/Image", store.generate_msgdef(
            "sensor_msgs/msg/Image", ros_version=2)[0])
        compressed = writer.register_msgdef("sensor_msgs/msg/CompressedImage",
                                            store.generate_msgdef(
                                                "sensor_msgs/msg/CompressedImage",
                                                ros_version=2)[0])
        for i in range(FRAMES):
            t = T0_NS + i * PERIOD_NS
            data = jpeg.tobytes()
            writer.write_message("/jpeg/image_raw/compressed", compressed, {
                "header": _header(t, "jpeg"), "format": "jpeg",
                "data": data[: len(data) // 2] if i in BAD_JPEG else data}, log_time=t)
            raw = rgb.tobytes()
            writer.write_message("/raw/image_raw", image, {
                "header": _header(t, "raw"), "height": HEIGHT, "width": WIDTH,
                "encoding": "rgb8", "is_bigendian": 0, "step": WIDTH * 3,
                "data": raw[: -WIDTH * 3] if i in BAD_RAW else raw}, log_time=t)
        writer.finish()
    return path


def _video_log(path: Path) -> Path:
    """foxglove.CompressedVideo H.264 from PyAV's encoder, one picture per message, its
    first keyframe left out so the stream starts with pictures that cannot decode."""
    codec = av.CodecContext.create("libx264", "w")
    codec.width, codec.height, codec.pix_fmt = WIDTH, HEIGHT, "yuv420p"
    codec.gop_size, codec.max_b_frames = GOP, 0
    codec.options = {"tune": "zerolatency", "x264-params": "repeat-headers=1"}
    codec.open()
    packets = []
    for i in range(FRAMES + DROPPED):
        picture = av.VideoFrame.from_ndarray(np.roll(scene_rgb(), i, axis=1), format="rgb24")
        packets.append(b"".join(bytes(p) for p in codec.encode(picture)))
    with path.open("wb") as f:
        writer = ProtobufWriter(f)
        for i, data in enumerate(packets[DROPPED:]):
            t = T0_NS + i * PERIOD_NS
            writer.write_message("/video/image", CompressedVideo(
                timestamp=Timestamp(seconds=t // 10**9, nanos=t % 10**9), frame_id="video",
                data=data, format="h264"), log_time=t, publish_time=t)
        writer.finish()
    return path


def _count(path: Path) -> dict[str, int]:
    counts: dict[str, int] = {}
    with path.open("rb") as f:
        for _, channel, _ in make_reader(f).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


@pytest.mark.parametrize(("topic", "bad"), [("/jpeg/image_raw/compressed", len(BAD_JPEG)),
                                            ("/raw/image_raw", len(BAD_RAW))])
def test_process_counts_undecodable_stills_and_goes_on(
        topic: str, bad: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _ros_log(tmp_path / "bad.mcap")
    out = tmp_path / "out.mcap"
    assert main(["process", str(log), "--topic", topic, "--red-pixels",
                 "--output-ns", "/image_converter", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert [line for line in err.splitlines() if line.startswith("warning:")] == [
        f"warning: {topic}: {bad} frames did not decode (copied, not processed)"]
    counts = _count(out)  # every input message copied, bad frames too
    assert counts[topic] == FRAMES and counts["/raw/image_raw"] == FRAMES
    with open_reader(out) as reader:
        centroids = [r.message for r in reader.messages(["/image_converter/red_centroid"])]
    assert len(centroids) == FRAMES - bad
    for centroid in centroids:
        assert isinstance(centroid, PointStamped)
        assert tuple(centroid.point[:2]) == pytest.approx(RED_CENTROID, abs=1.0)


def test_process_counts_video_pictures_before_the_first_keyframe(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _video_log(tmp_path / "video.mcap")
    out = tmp_path / "out.mcap"
    assert main(["process", str(log), "--topic", "/video/image", "--red-pixels",
                 "--output-ns", "/image_converter", "-o", str(out)]) == 0
    before_keyframe = GOP - DROPPED
    err = capsys.readouterr().err
    assert [line for line in err.splitlines() if line.startswith("warning:")] == [
        f"warning: /video/image: {before_keyframe} frames did not decode "
        "(copied, not processed)"]
    assert _count(out)["/video/image"] == FRAMES
    with open_reader(out) as reader:
        centroids = list(reader.messages(["/image_converter/red_centroid"]))
    assert len(centroids) == FRAMES - before_keyframe


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("warning:")]


def test_info_verify_decodes_every_frame_and_counts_the_bad_ones(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _ros_log(tmp_path / "bad.mcap")
    assert main(["info", str(log)]) == 0
    out, err = capsys.readouterr()
    assert "frames:    not decoded (--verify decodes every one)" in out.splitlines()
    assert _warnings(err) == []  # the index alone sees nothing wrong
    assert main(["info", "--verify", str(log)]) == 0
    out, err = capsys.readouterr()
    bad = len(BAD_JPEG) + len(BAD_RAW)
    assert f"frames:    {2 * FRAMES - bad} of {2 * FRAMES} decoded, {bad} did not " \
           "(see the warnings)" in out.splitlines()
    assert _warnings(err) == [
        f"warning: /jpeg/image_raw/compressed: {len(BAD_JPEG)} frames did not decode",
        f"warning: /raw/image_raw: {len(BAD_RAW)} frames did not decode"]


def test_info_verify_counts_video_pictures_before_the_first_keyframe(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _video_log(tmp_path / "video.mcap")
    assert main(["info", "--verify", str(log)]) == 0
    out, err = capsys.readouterr()
    assert _warnings(err) == [f"warning: /video/image: {GOP - DROPPED} frames did not decode"]
    assert f"frames:    {FRAMES - GOP + DROPPED} of {FRAMES} decoded" in out


def test_convert_leaves_out_and_counts_undecodable_frames(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _ros_log(tmp_path / "bad.mcap")
    out = tmp_path / "png.mcap"
    assert main(["convert", str(log), str(out), "--compress", "png", "--no-progress"]) == 0
    assert _warnings(capsys.readouterr().err) == [
        f"warning: /raw/image_raw: {len(BAD_RAW)} frames did not decode (left out)"]
    counts = _count(out)
    assert counts["/raw/image_raw/compressed"] == FRAMES - len(BAD_RAW)
    assert counts["/jpeg/image_raw/compressed"] == FRAMES  # not re-encoded: copied as stored
    back = tmp_path / "raw.mcap"
    assert main(["convert", str(log), str(back), "--decompress", "--no-progress"]) == 0
    assert _warnings(capsys.readouterr().err) == [
        f"warning: /jpeg/image_raw/compressed: {len(BAD_JPEG)} frames did not decode "
        "(left out)"]
    with open_reader(back) as reader:
        images = [r.message for r in reader.messages(["/jpeg/image_raw"])]
    assert len(images) == FRAMES - len(BAD_JPEG)
    assert all(isinstance(i, Image) and i.encoding == "bgr8" for i in images)


def test_convert_copies_a_topic_whose_encoding_camlog_does_not_read(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = ros2_typestore()
    log = tmp_path / "yuv411.mcap"
    with log.open("wb") as f:
        writer = Ros2Writer(f)
        image = writer.register_msgdef("sensor_msgs/msg/Image", store.generate_msgdef(
            "sensor_msgs/msg/Image", ros_version=2)[0])
        for i in range(3):
            t = T0_NS + i * PERIOD_NS
            writer.write_message("/cam/image_raw", image, {
                "header": _header(t, "cam"), "height": 4, "width": 4, "encoding": "yuv411",
                "is_bigendian": 0, "step": 6, "data": bytes(24)}, log_time=t)
        writer.finish()
    out = tmp_path / "out.mcap"
    assert main(["convert", str(log), str(out), "--compress", "jpeg", "--no-progress"]) == 0
    (warning,) = _warnings(capsys.readouterr().err)
    assert warning.startswith("warning: /cam/image_raw: ")
    assert "unsupported image encoding 'yuv411'" in warning
    assert warning.endswith("; copied unchanged")
    assert _count(out) == {"/cam/image_raw": 3}


def test_view_counts_undecodable_frames_and_shows_the_rest(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _ros_log(tmp_path / "bad.mcap")
    rrd = tmp_path / "bad.rrd"
    assert main(["view", str(log), "-o", str(rrd), "--no-progress"]) == 0
    warnings = _warnings(capsys.readouterr().err)
    assert [w.split(" (")[0] for w in warnings] == [
        f"warning: /jpeg/image_raw/compressed: {len(BAD_JPEG)} frames did not decode",
        f"warning: /raw/image_raw: {len(BAD_RAW)} frames did not decode"]
    assert all("(not shown; first at log time" in w for w in warnings)
    rec = load_rrd(rrd)
    assert rec.count("/world/jpeg/image", "EncodedImage:blob") == FRAMES - len(BAD_JPEG)
    assert rec.count("/world/raw/image", "Image:buffer") == FRAMES - len(BAD_RAW)


def test_view_counts_video_pictures_before_the_first_keyframe(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _video_log(tmp_path / "video.mcap")
    rrd = tmp_path / "video.rrd"
    assert main(["view", str(log), "-o", str(rrd), "--no-progress"]) == 0
    (warning,) = _warnings(capsys.readouterr().err)
    assert warning.startswith(f"warning: /video/image: {GOP - DROPPED} frames did not decode "
                              "(not shown; ")
    assert load_rrd(rrd).count("/world/video/video", "VideoStream:sample") == \
        FRAMES - GOP + DROPPED


def _cut_every(source: Path, out: Path, topic: str, every: int) -> int:
    """Copy an MCAP log with the mcap libraries, each ``every``-th image of ``topic`` with its
    raw buffer cut in half; returns how many were cut."""
    from mcap_ros2.decoder import DecoderFactory

    cut = 0
    with source.open("rb") as f, out.open("wb") as g:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        writer = Ros2Writer(g)
        schemas: dict[int, object] = {}
        index = 0
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            assert schema is not None
            if schema.id not in schemas:
                schemas[schema.id] = writer.register_msgdef(schema.name, schema.data.decode())
            if channel.topic == topic:
                if index % every == every - 1:
                    decoded.data = bytes(decoded.data)[: len(decoded.data) // 2]
                    cut += 1
                index += 1
            writer.write_message(channel.topic, schemas[schema.id], decoded,
                                 log_time=message.log_time, publish_time=message.publish_time)
        writer.finish()
    return cut


def test_calibrate_leaves_out_undecodable_frames_and_says_so(
        mono_calibration_log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = mono_calibration_log.parent.parent / "mono.mcap"
    topic = "/simple_camera/image_raw"
    damaged = tmp_path / "damaged.mcap"
    cut = _cut_every(source, damaged, topic, every=10)
    total = _count(source)[topic]
    assert 0 < cut < total
    out = tmp_path / "cal"
    assert main(["calibrate", str(damaged), "--size", "7x6", "--square", "0.01",
                 "-o", str(out), "--no-progress"]) == 0
    assert _warnings(capsys.readouterr().err) == [
        f"warning: {topic}: {cut} frames did not decode and were left out"]
    (camera,) = json.loads((out / "calibration.json").read_text())["cameras"]
    assert camera["frames"] == total - cut
    assert _count(out / "calibration.mcap")[topic] == total  # the input, copied whole


def _damaged_stills_log(path: Path) -> Path:
    """JPEG and PNG topics whose frames are whole, cut short (neither decodes) or, for the
    JPEG, with bytes of its entropy-coded data overwritten (it decodes, and libjpeg prints
    ``Corrupt JPEG data: ...`` on fd 2)."""
    bgr = cv2.cvtColor(scene_rgb(), cv2.COLOR_RGB2BGR)
    jpeg = cv2.imencode(".jpg", bgr)[1].tobytes()
    png = cv2.imencode(".png", bgr)[1].tobytes()
    at = len(jpeg) * 9 // 10  # in the entropy-coded data, past the headers
    corrupt = jpeg[:at] + b"\xff\x00" * 32 + jpeg[at + 64:]
    frames = {"/jpeg/image_raw/compressed": [jpeg, jpeg[: len(jpeg) // 2], corrupt, jpeg],
              "/png/image_raw/compressed": [png, png[: len(png) // 2], png[:-20], png]}
    with open_writer(path) as writer:
        for topic, datas in frames.items():
            fmt = topic.split("/")[1]
            for i, data in enumerate(datas):
                writer.write(topic, CompressedImage(T0_NS + i * PERIOD_NS, "cam", fmt, data))
    return path


@pytest.mark.slow
def test_decoders_own_messages_stay_off_the_terminal(tmp_path: Path) -> None:
    log = _damaged_stills_log(tmp_path / "damaged.mcap")
    done = subprocess.run(
        [sys.executable, "-m", "camlog", "process", str(log), "--topic",
         "/jpeg/image_raw/compressed", "--topic", "/png/image_raw/compressed", "--red-pixels",
         "-o", str(tmp_path / "out.mcap")],
        cwd=REPO_ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines() == [
        "warning: /jpeg/image_raw/compressed: 1 frames did not decode (copied, not processed)",
        "warning: /png/image_raw/compressed: 2 frames did not decode (copied, not processed)"]


def test_the_decoders_message_lines_are_told_from_others() -> None:
    from camlog.cli.decoder_messages import forward

    data = (b"Corrupt JPEG data: 3 extraneous bytes before marker 0xd9\n0/40 frames\r\n"
            b"Premature end of JPEG file\r\nlibpng error: IDAT: CRC error\n"
            b"camlog process: error: Corrupt JPEG data: no\nCorrupt JPEG")
    assert forward(data) == (b"0/40 frames\r\ncamlog process: error: Corrupt JPEG data: no\n",
                             b"Corrupt JPEG")
