"""``convert_log``: byte-exact round trips over every format, filtering, image re-encoding."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from camlog.logs.convert import convert_log
from camlog.requests.logs import ConvertRequest
from replay import (
    CompressedImage,
    Image,
    LogFormatError,
    LogReadError,
    OptionError,
    OutputError,
    TopicError,
    open_reader,
)
from tests.outputs import temp_outputs
from tests.recordings import chunked_camera_log, corrupt_middle_chunk
from tests.replay.samples import OUTPUT_NAMES, T0_NS, every_kind, write_log
from tests.rrd import rerun_cli

Raw = tuple[str, int, bytes]


def raw_messages(path: Path) -> list[Raw]:
    with open_reader(path) as reader:
        return [(r.topic, r.log_time_ns, bytes(r.data)) for r in reader.raw_messages()]


def anyreader_count(path: Path) -> int:
    with AnyReader([path], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        return sum(1 for conn, _, raw in reader.messages()
                   if reader.deserialize(raw, conn.msgtype) is not None)


@pytest.fixture(scope="module")
def sample_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Every message kind and image encoding camlog writes."""
    path = tmp_path_factory.mktemp("samples") / "samples.mcap"
    write_log(path, every_kind())
    return path


@pytest.mark.parametrize("fmt", ["rosbag2", "rosbag2-sqlite3", "ros1"])
def test_round_trip_through_every_format_is_byte_exact(
        fmt: str, sample_log: Path, red_processed_log: Path, tmp_path: Path) -> None:
    for source in (sample_log, red_processed_log):
        middle = tmp_path / f"{source.stem}_{OUTPUT_NAMES[fmt]}"
        back = tmp_path / f"{source.stem}_back.mcap"
        there = convert_log(ConvertRequest(input=source, output=middle, format=fmt, progress=False))
        convert_log(ConvertRequest(input=middle, output=back, progress=False))
        original = raw_messages(source)
        assert there.messages == len(original) and there.reencoded == 0
        # CDR -> ROS1 -> CDR (rosbags) is byte-exact for camlog's messages as well
        assert raw_messages(back) == original
        assert anyreader_count(middle) == len(original)
        assert anyreader_count(back) == len(original)


@pytest.mark.slow
def test_rerun_reads_converted_mcap_logs(sample_log: Path, tmp_path: Path) -> None:
    bag = tmp_path / "bag2"
    convert_log(ConvertRequest(input=sample_log, output=bag, format="rosbag2", progress=False))
    back = tmp_path / "back.mcap"
    convert_log(ConvertRequest(input=bag, output=back, progress=False))
    for mcap in (back, bag / "bag2.mcap"):
        done = rerun_cli("mcap", "convert", str(mcap), "-o", str(tmp_path / "x.rrd"),
                         cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        printed = rerun_cli("rrd", "print", str(tmp_path / "x.rrd"), cwd=tmp_path)
        assert "Pinhole:image_from_camera" in printed.stdout
        (tmp_path / "x.rrd").unlink()


def test_topics_and_time_window(red_processed_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "part.bag"
    convert_log(ConvertRequest(input=red_processed_log, output=out,
                               topics=["/stereo_camera/left/*"], start=0.2, end=0.4,
                               progress=False))
    got = raw_messages(out)
    with open_reader(red_processed_log) as reader:
        start = reader.start_ns
    assert start is not None
    # the camera's own topics and the processor outputs written under its namespace
    topics = {f"/stereo_camera/left/{name}" for name in (
        "image_raw", "camera_info", "ground_truth/red_block", "edges", "output_video",
        "red_centroid", "red_count")}
    assert {t for t, _, _ in got} == topics
    assert all(start + 200_000_000 <= t < start + 400_000_000 for _, t, _ in got)
    assert len(got) == len(topics) * 6  # frames 6..11 at 30 Hz


def test_compress_png_is_lossless_and_renames(red_log: Path, tmp_path: Path) -> None:
    packed = tmp_path / "png.mcap"
    result = convert_log(ConvertRequest(input=red_log, output=packed, compress="png",
                                        progress=False))
    assert result.renamed == {f"/stereo_camera/{s}/image_raw": f"/stereo_camera/{s}/image_raw"
                              "/compressed" for s in ("left", "right")}
    with open_reader(packed) as reader:
        assert reader.topics["/stereo_camera/left/image_raw/compressed"].msgtype == \
            "sensor_msgs/msg/CompressedImage"
        assert "/stereo_camera/left/image_raw" not in reader.topics
    unpacked = tmp_path / "raw.mcap"
    convert_log(ConvertRequest(input=packed, output=unpacked, decompress=True, progress=False))
    with open_reader(red_log) as a, open_reader(unpacked) as b:
        topics = ["/stereo_camera/left/image_raw"]
        before = [r.message for r in a.messages(topics)]
        after = [r.message for r in b.messages(topics)]
    assert len(before) == 20 and before == after  # stamps, frames and pixels identical


def test_compress_jpeg_and_its_limits(tmp_path: Path) -> None:
    log = tmp_path / "mixed.mcap"
    gray = np.tile(np.arange(64, dtype=np.uint8) * 4, (48, 1))
    write_log(log, [("/a/image_raw", T0_NS, Image(T0_NS, "a", "mono8", gray))])
    out = tmp_path / "jpeg.mcap"
    convert_log(ConvertRequest(input=log, output=out, compress="jpeg", progress=False))
    with open_reader(out) as reader:
        (record,) = reader.messages()
    assert isinstance(record.message, CompressedImage) and "jpeg" in record.message.format
    deep = tmp_path / "deep.mcap"
    write_log(deep, [("/d/image_raw", T0_NS, Image(T0_NS, "d", "mono16",
                                                   gray.astype(np.uint16) * 200))])
    # JPEG cannot hold 16 bits: that topic goes to lossless PNG instead, with a warning
    result = convert_log(ConvertRequest(input=deep, output=tmp_path / "deep_jpeg.mcap",
                                        compress="jpeg", progress=False))
    assert result.warnings == ["/d/image_raw: jpeg cannot hold its images losslessly; "
                               "stored as png"]
    with open_reader(tmp_path / "deep_jpeg.mcap") as reader:
        (record,) = reader.frames()
    assert record.topic == "/d/image_raw/compressed" and record.message.source == "png"
    assert np.array_equal(record.message.pixels, gray.astype(np.uint16) * 200)
    both = tmp_path / "both.mcap"
    convert_log(ConvertRequest(input=log, output=both, compress="png", progress=False))
    write_log(tmp_path / "two.mcap", [
        ("/a/image_raw", T0_NS, Image(T0_NS, "a", "mono8", gray)),
        ("/a/image_raw/compressed", T0_NS + 1, raw_compressed(both))])
    with pytest.raises(TopicError, match="two /a/image_raw/compressed topics"):
        convert_log(ConvertRequest(input=tmp_path / "two.mcap", output=tmp_path / "c.mcap",
                                   compress="png", progress=False))
    with pytest.raises(OptionError, match="exclude each other"):
        convert_log(ConvertRequest(input=log, output=tmp_path / "x.mcap", compress="png",
                                   decompress=True, progress=False))


def raw_compressed(path: Path) -> CompressedImage:
    with open_reader(path) as reader:
        (record,) = reader.messages()
    assert isinstance(record.message, CompressedImage)
    return record.message


def test_damaged_inputs(tmp_path: Path) -> None:
    log = tmp_path / "bad.mcap"
    stamps = chunked_camera_log(log)
    damaged_from = corrupt_middle_chunk(log)
    with pytest.raises(LogReadError, match="corrupt"):
        convert_log(ConvertRequest(input=log, output=tmp_path / "out.bag", progress=False))
    assert not (tmp_path / "out.bag").exists() and temp_outputs(tmp_path) == []
    result = convert_log(ConvertRequest(input=log, output=tmp_path / "out.bag", recover=True,
                                        progress=False))
    intact = sum(1 for s in stamps if s < damaged_from)
    (skipped,) = [w for w in result.warnings if "skipped the damaged chunk" in w]
    lost = int(skipped.split(": ")[-1].split()[0])  # "...: N messages lost, log times ..."
    assert 0 < lost < 2 * len(stamps) - 2 * intact  # the chunks after it are read too
    assert result.messages == 2 * len(stamps) - lost


def test_bad_arguments(red_log: Path, tmp_path: Path) -> None:
    with pytest.raises(OutputError, match="is the input"):
        convert_log(ConvertRequest(input=red_log, output=red_log, progress=False))
    with pytest.raises(LogFormatError, match="cannot tell the log format"):
        convert_log(ConvertRequest(input=red_log, output=tmp_path / "out.txt", progress=False))
    with pytest.raises(LogFormatError, match="unknown log format"):
        convert_log(ConvertRequest(input=red_log, output=tmp_path / "out", format="hdf5",
                                   progress=False))
    with pytest.raises(OptionError, match="--end"):
        convert_log(ConvertRequest(input=red_log, output=tmp_path / "o.mcap", start=2, end=1,
                                   progress=False))
    assert sorted(p.name for p in tmp_path.iterdir()) == []
