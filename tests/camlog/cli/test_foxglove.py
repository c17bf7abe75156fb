"""Logs in Foxglove's schemas (protobuf through mcap_protobuf and foxglove_schemas_protobuf,
JSON as Foxglove lays it out), channels camlog does not understand, and H.264 video."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import av
import cv2
import numpy as np
import pytest
from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage as FoxCompressed
from foxglove_schemas_protobuf.LaserScan_pb2 import LaserScan
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
from google.protobuf.timestamp_pb2 import Timestamp
from mcap.reader import make_reader
from mcap.writer import Writer as McapWriter
from mcap_protobuf.writer import Writer as ProtobufWriter
from mcap_ros2.writer import Writer as Ros2Writer

from camlog.cli import main
from replay import PointStamped, open_reader
from replay.frames import psnr_db
from replay.wire import ros2_typestore
from tests.encodings import HEIGHT, RED_CENTROID, WIDTH, scene_rgb
from tests.rrd import load_rrd, rerun_cli

T0_NS = 2_000_000_000
PERIOD_NS = 50_000_000
K = [80.0, 0.0, 31.5, 0.0, 80.0, 23.5, 0.0, 0.0, 1.0]


def _stamp(stamp_ns: int) -> Timestamp:
    return Timestamp(seconds=stamp_ns // 10**9, nanos=stamp_ns % 10**9)


@pytest.fixture(scope="module")
def foxglove_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three frames of the red-square scene as foxglove.RawImage, CompressedImage (PNG) and
    CameraCalibration in protobuf, RawImage in JSON, plus a LaserScan and a schemaless
    JSON channel."""
    path = tmp_path_factory.mktemp("foxglove") / "fox.mcap"
    rgb = scene_rgb()
    ok, png = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    assert ok
    with path.open("wb") as f:
        writer = ProtobufWriter(f)
        for i in range(3):
            t = T0_NS + i * PERIOD_NS
            writer.write_message("/fox/image", RawImage(
                timestamp=_stamp(t), frame_id="fox", width=WIDTH, height=HEIGHT,
                encoding="rgb8", step=WIDTH * 3, data=rgb.tobytes()), log_time=t, publish_time=t)
            writer.write_message("/fox/calibration", CameraCalibration(
                timestamp=_stamp(t), frame_id="fox", width=WIDTH, height=HEIGHT,
                distortion_model="plumb_bob", D=[0.0] * 5, K=K, R=[1, 0, 0, 0, 1, 0, 0, 0, 1],
                P=[80.0, 0, 31.5, 0, 0, 80.0, 23.5, 0, 0, 0, 1, 0]), log_time=t, publish_time=t)
            writer.write_message("/fox_png/image", FoxCompressed(
                timestamp=_stamp(t), frame_id="fox_png", data=png.tobytes(), format="png"),
                log_time=t, publish_time=t)
            writer.write_message("/scan", LaserScan(timestamp=_stamp(t), frame_id="laser",
                                                    ranges=[1.0, 2.0, float(i)]),
                                 log_time=t, publish_time=t)
        writer.finish()
    # JSON channels appended with the plain mcap writer to a second file, then merged
    # through camlog would hide what is tested: write them into their own log instead
    return path


@pytest.fixture(scope="module")
def json_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """foxglove.RawImage in JSON (bytes in base64, time as sec/nsec) and a schemaless
    JSON channel, written with the mcap library."""
    path = tmp_path_factory.mktemp("json") / "json.mcap"
    rgb = scene_rgb()
    with path.open("wb") as f:
        writer = McapWriter(f)
        writer.start(profile="", library="test")
        schema = writer.register_schema("foxglove.RawImage", "jsonschema",
                                        json.dumps({"type": "object"}).encode())
        image = writer.register_channel("/fox_json/image", "json", schema)
        notes = writer.register_channel("/notes", "json", 0)
        for i in range(3):
            t = T0_NS + i * PERIOD_NS
            message = {"timestamp": {"sec": t // 10**9, "nsec": t % 10**9},
                       "frame_id": "fox_json", "width": WIDTH, "height": HEIGHT,
                       "encoding": "bgr8", "step": WIDTH * 3,
                       "data": base64.b64encode(rgb[:, :, ::-1].tobytes()).decode()}
            writer.add_message(image, t, json.dumps(message).encode(), t)
            writer.add_message(notes, t, json.dumps({"note": i}).encode(), t)
        writer.finish()
    return path


def test_info_lists_foxglove_and_unknown_channels(foxglove_log: Path, json_log: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", str(foxglove_log)]) == 0
    out = capsys.readouterr().out
    assert "foxglove.RawImage" in out and "rgb8 64x48 (protobuf)" in out
    assert "64x48 plumb_bob (protobuf)" in out and "png 64x48 (protobuf)" in out
    (scan,) = [line for line in out.splitlines() if "/scan" in line]
    assert "foxglove.LaserScan" in scan and "(protobuf; copied, not decoded)" in scan
    assert main(["info", str(json_log)]) == 0
    out = capsys.readouterr().out
    assert "bgr8 64x48 (json)" in out
    (notes,) = [line for line in out.splitlines() if "/notes" in line]
    assert "(no schema)" in notes and "(json; copied, not decoded)" in notes


@pytest.mark.parametrize(("log", "topic"), [("foxglove", "/fox/image"),
                                            ("foxglove", "/fox_png/image"),
                                            ("json", "/fox_json/image")])
def test_process_reads_foxglove_images(log: str, topic: str, foxglove_log: Path,
                                       json_log: Path, tmp_path: Path) -> None:
    source = foxglove_log if log == "foxglove" else json_log
    out = tmp_path / "out.mcap"
    assert main(["process", str(source), "--topic", topic, "--red-pixels",
                 "--output-ns", "/image_converter", "-o", str(out)]) == 0
    with open_reader(out) as reader:
        centroids = [r.message for r in reader.messages(["/image_converter/red_centroid"])]
        assert reader.topics[topic].count == 3  # the input channel copied through
    assert len(centroids) == 3
    for centroid in centroids:
        assert isinstance(centroid, PointStamped)
        assert tuple(centroid.point[:2]) == pytest.approx(RED_CENTROID, abs=0.01)


def _messages(path: Path, topic: str) -> list[tuple[str, str, bytes]]:
    """(schema name, message encoding, bytes) of a topic, read with the mcap library."""
    with path.open("rb") as f:
        return [(schema.name if schema else "", channel.message_encoding, message.data)
                for schema, channel, message in make_reader(f).iter_messages(topics=[topic])]


def test_convert_copies_channels_it_does_not_understand(
        foxglove_log: Path, json_log: Path, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "copy.mcap"
    assert main(["convert", str(foxglove_log), str(out)]) == 0
    for topic in ("/scan", "/fox/image", "/fox/calibration"):
        assert _messages(out, topic) == _messages(foxglove_log, topic)  # byte for byte
    out = tmp_path / "json_copy.mcap"
    assert main(["convert", str(json_log), str(out)]) == 0
    assert _messages(out, "/notes") == _messages(json_log, "/notes")
    capsys.readouterr()
    bag = tmp_path / "bag"
    assert main(["convert", str(foxglove_log), str(bag)]) == 0
    err = capsys.readouterr().err
    assert ("/scan (foxglove.LaserScan, protobuf) left out: rosbag2 (mcap) holds ROS messages"
            " only; write MCAP to keep it") in err


@pytest.mark.slow
def test_view_shows_foxglove_images_with_their_calibration(foxglove_log: Path,
                                                          tmp_path: Path) -> None:
    out = tmp_path / "fox.rrd"
    assert main(["view", str(foxglove_log), "-o", str(out), "--no-progress"]) == 0
    recording = load_rrd(out)
    assert recording.count("/world/fox/image", "Image:buffer") == 3
    assert recording.count("/world/fox_png/image", "EncodedImage:blob") == 3
    (pinhole,) = recording.column("/world/fox", "Pinhole:image_from_camera")[:1]
    assert pinhole[0][:: 4] == pytest.approx([80.0, 80.0, 1.0])  # column-major K: fx, fy
    assert pinhole[0][6:8] == pytest.approx([31.5, 23.5])
    converted = rerun_cli("mcap", "convert", str(foxglove_log), "-o", "x.rrd", cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr


def test_profile_foxglove_writes_foxglove_schemas(tmp_path: Path) -> None:
    source = _moving_square_log(tmp_path / "ros.mcap", frames=2)
    out = tmp_path / "fox.mcap"
    assert main(["convert", str(source), str(out), "--profile", "foxglove"]) == 0
    ((name, encoding, data), _) = _messages(out, "/cam/image_raw")
    assert (name, encoding) == ("foxglove.RawImage", "protobuf")
    image = RawImage.FromString(data)
    assert (image.width, image.height, image.encoding) == (WIDTH, HEIGHT, "rgb8")


def _moving_square_log(path: Path, *, frames: int) -> Path:
    """``frames`` rgb8 images of the scene with the square moving right 2 px per frame,
    written with mcap_ros2."""
    msgdef, _ = ros2_typestore().generate_msgdef("sensor_msgs/msg/Image", ros_version=2)
    with path.open("wb") as f:
        writer = Ros2Writer(f)
        schema = writer.register_msgdef("sensor_msgs/msg/Image", msgdef)
        for i in range(frames):
            rgb = np.roll(scene_rgb(), 2 * i, axis=1)
            t = T0_NS + i * PERIOD_NS
            writer.write_message("/cam/image_raw", schema, {
                "header": {"stamp": {"sec": t // 10**9, "nanosec": t % 10**9},
                           "frame_id": "cam"},
                "height": HEIGHT, "width": WIDTH, "encoding": "rgb8", "is_bigendian": 0,
                "step": WIDTH * 3, "data": rgb.tobytes()}, log_time=t)
        writer.finish()
    return path


@pytest.mark.slow
def test_h264_video_through_convert_process_and_view(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    frames = 12
    source = _moving_square_log(tmp_path / "raw.mcap", frames=frames)
    video = tmp_path / "video.mcap"
    assert main(["convert", str(source), str(video), "--compress", "h264"]) == 0
    out = capsys.readouterr().out
    assert "renamed /cam/image_raw -> /cam/image_raw/video" in out
    psnr = float(out.split("h264 PSNR ")[1].split(" dB")[0])
    assert psnr > 30.0
    # PyAV alone decodes what camlog wrote, picture for picture
    samples = _messages(video, "/cam/image_raw/video")
    assert len(samples) == frames and {s[:2] for s in samples} == {
        ("foxglove.CompressedVideo", "protobuf")}
    from foxglove_schemas_protobuf.CompressedVideo_pb2 import CompressedVideo

    codec = av.CodecContext.create("h264", "r")
    for i, (_, _, data) in enumerate(samples):
        message = CompressedVideo.FromString(data)
        assert message.format == "h264"
        (picture,) = codec.decode(av.Packet(message.data))
        expected = np.roll(scene_rgb(), 2 * i, axis=1)
        assert psnr_db(expected, picture.to_ndarray(format="rgb24")) > 30.0
    processed = tmp_path / "processed.mcap"
    assert main(["process", str(video), "--topic", "/cam/image_raw/video", "--red-pixels",
                 "--output-ns", "/image_converter",
                 "--drop-input", "-o", str(processed)]) == 0
    with open_reader(processed) as reader:
        centroids = [r.message for r in reader.messages(["/image_converter/red_centroid"])]
    assert len(centroids) == frames
    for i, centroid in enumerate(centroids):
        assert isinstance(centroid, PointStamped)
        u, v = RED_CENTROID
        assert tuple(centroid.point[:2]) == pytest.approx((u + 2 * i, v), abs=0.5)
    rrd = tmp_path / "video.rrd"
    assert main(["view", str(video), "-o", str(rrd), "--no-progress"]) == 0
    assert load_rrd(rrd).count("/world/cam/video", "VideoStream:sample") == frames
    converted = rerun_cli("mcap", "convert", str(video), "-o", "v.rrd", cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr


def test_crf_trades_size_for_quality(tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    source = _moving_square_log(tmp_path / "raw.mcap", frames=6)
    sizes, psnr = {}, {}
    for crf in (10, 40):
        out = tmp_path / f"crf{crf}.mcap"
        assert main(["convert", str(source), str(out), "--compress", "h264", "--crf",
                     str(crf), "--no-progress"]) == 0
        printed = capsys.readouterr().out
        psnr[crf] = float(printed.split("h264 PSNR ")[1].split(" dB")[0])
        sizes[crf] = sum(len(data) for _, _, data in _messages(out, "/cam/image_raw/video"))
    assert sizes[40] < sizes[10] and psnr[40] < psnr[10]
    with pytest.raises(SystemExit):
        main(["convert", str(source), str(tmp_path / "x.mcap"), "--compress", "h264",
              "--crf", "52"])
    assert "--crf: expected" in capsys.readouterr().err
