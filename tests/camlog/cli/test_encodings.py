"""Every sensor_msgs/Image encoding, in a log written by the mcap library's own ROS 2 writer
(``mcap_ros2``), through ``camlog info``, ``process``, ``view`` and ``convert``, and
accepted by rerun's own MCAP loader."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mcap_ros2.writer import Writer as Ros2Writer

from camlog.cli import main
from replay import CompressedImage, PointStamped, open_reader
from replay.frames import decode_frame
from replay.wire import ros2_typestore
from tests.encodings import HEIGHT, RED_CENTROID, WIDTH, Case, colour_cases, depth_cases
from tests.rrd import load_rrd, rerun_cli

CASES = colour_cases() + depth_cases()
T0_NS = 1_000_000_000


def topic_of(case: Case) -> str:
    return f"/enc_{case.encoding}/image_raw"


def entity_of(case: Case) -> str:
    return f"/world/enc_{case.encoding}/image"


@pytest.fixture(scope="module")
def encodings_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two frames of every case, one topic per encoding, written by mcap_ros2."""
    path = tmp_path_factory.mktemp("encodings") / "encodings.mcap"
    msgdef, _ = ros2_typestore().generate_msgdef("sensor_msgs/msg/Image", ros_version=2)
    with path.open("wb") as f:
        writer = Ros2Writer(f)
        schema = writer.register_msgdef("sensor_msgs/msg/Image", msgdef)
        for i in range(2):
            for case in CASES:
                px = np.ascontiguousarray(case.pixels)
                stamp = T0_NS + i * 100_000_000
                writer.write_message(topic_of(case), schema, {
                    "header": {"stamp": {"sec": stamp // 10**9, "nanosec": stamp % 10**9},
                               "frame_id": case.encoding},
                    "height": HEIGHT, "width": WIDTH, "encoding": case.encoding,
                    "is_bigendian": 0, "step": px.nbytes // px.shape[0],
                    "data": px.tobytes()}, log_time=stamp)
        writer.finish()
    return path


def test_info_lists_every_encoding(encodings_log: Path, capsys: pytest.CaptureFixture[str]
                                   ) -> None:
    assert main(["info", str(encodings_log)]) == 0
    lines = capsys.readouterr().out.splitlines()
    for case in CASES:
        (line,) = [row for row in lines if f" {topic_of(case)} " in f" {row} "]
        assert line.rstrip().endswith(f"{case.encoding} 64x48")


@pytest.mark.parametrize("case", [c for c in CASES if c.colour], ids=lambda c: c.encoding)
def test_process_finds_the_red_square(case: Case, encodings_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "out.mcap"
    assert main(["process", str(encodings_log), "--topic", topic_of(case), "--red-pixels",
                 "--output-ns", "/image_converter",
                 "--drop-input", "-o", str(out)]) == 0
    with open_reader(out) as reader:
        centroids = [r.message for r in reader.messages(["/image_converter/red_centroid"])]
    assert len(centroids) == 2
    for centroid in centroids:
        assert isinstance(centroid, PointStamped) and centroid.frame_id == case.encoding
        within = 0.5 if case.margin else 0.01  # demosaicing shifts an edge a little
        assert tuple(centroid.point[:2]) == pytest.approx(RED_CENTROID, abs=within)


@pytest.mark.slow
def test_view_shows_every_topic_and_depth_as_depth(encodings_log: Path, tmp_path: Path
                                                    ) -> None:
    out = tmp_path / "enc.rrd"
    assert main(["view", str(encodings_log), "-o", str(out), "--no-progress"]) == 0
    recording = load_rrd(out)
    for case in CASES:
        column = "DepthImage:buffer" if case.depth_m is not None else "Image:buffer"
        assert recording.count(entity_of(case), column) == 2, case.encoding
    (meter,) = {m[0] for m in recording.column(entity_of(depth_cases()[0]), "DepthImage:meter")}
    assert meter == pytest.approx(1000.0)  # 16UC1: millimetres


@pytest.mark.slow
def test_rerun_reads_the_log_too(encodings_log: Path, tmp_path: Path) -> None:
    converted = rerun_cli("mcap", "convert", str(encodings_log), "-o", "enc.rrd", cwd=tmp_path)
    assert converted.returncode == 0, converted.stderr


def test_convert_compress_works_per_topic(encodings_log: Path, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "jpeg.mcap"
    depth = [c for c in CASES if c.depth_m is not None]
    chosen = ["/enc_rgb8/image_raw", *(topic_of(c) for c in depth)]
    assert main(["convert", str(encodings_log), str(out), "--compress", "jpeg",
                 "--topics", *chosen]) == 0
    err = capsys.readouterr().err
    assert "/enc_16UC1/image_raw: jpeg cannot hold its images losslessly; stored as " \
           "compressedDepth" in err
    assert "/enc_32FC1/image_raw: jpeg cannot hold its images losslessly; copied" in err
    with open_reader(out) as reader:
        assert reader.topics["/enc_rgb8/image_raw/compressed"].count == 2
        assert reader.topics["/enc_32FC1/image_raw"].count == 2  # copied as it was
        (first, _) = [r.message for r in reader.messages(["/enc_16UC1/image_raw/compressed"])]
    assert isinstance(first, CompressedImage) and "compressedDepth" in first.format
    assert depth[0].depth_m is not None
    frame = decode_frame(first)
    assert frame.depth_unit_m is not None
    np.testing.assert_allclose(frame.pixels * frame.depth_unit_m, depth[0].depth_m)  # lossless
