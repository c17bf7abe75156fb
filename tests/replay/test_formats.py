"""Every writer x format: round trips, filters, ordering, atomic output, open errors."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from replay import (
    EncodingError,
    Image,
    LogFormatError,
    LogReadError,
    LogWriteError,
    OutputError,
    PointStamped,
    RawMessage,
    Text,
    TopicError,
    open_reader,
    open_writer,
)
from replay.formats import detect_format, format_for_output
from replay.wire import CDR, msgtype_of, ros2_typestore

from .samples import T0_NS, WRITE_FORMATS, Entry, random_pixels, read_log, write_log

#: writer format -> reader format_name
READ_AS = {
    "mcap": "mcap",
    "rosbag2": "rosbag2 (mcap)",
    "rosbag2-sqlite3": "rosbag2 (sqlite3)",
    "ros1": "ros1",
}


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_round_trip_every_message_kind(
    fmt: str, log_path: Callable[[str], Path], sample_entries: list[Entry]
) -> None:
    path = log_path(fmt)
    write_log(path, sample_entries, fmt=fmt)
    assert read_log(path) == sample_entries
    with open_reader(path) as reader:
        assert reader.format_name == READ_AS[fmt]
        assert reader.message_count == len(sample_entries)
        assert (reader.start_ns, reader.end_ns) == (sample_entries[0][1], sample_entries[-1][1])
        assert {name: (info.msgtype, info.count) for name, info in reader.topics.items()} == {
            topic: (msgtype_of(message), 1) for topic, _, message in sample_entries
        }


@pytest.mark.parametrize(("name", "fmt"), [("a.mcap", "mcap"), ("a.bag", "ros1"), ("a", "rosbag2")])
def test_output_format_from_suffix(name: str, fmt: str) -> None:
    assert format_for_output(Path(name)) == fmt
    assert format_for_output(Path(name), "rosbag2-sqlite3") == "rosbag2-sqlite3"


def test_unknown_output_format_or_suffix(tmp_path: Path) -> None:
    with pytest.raises(LogFormatError, match="'hdf5'"):
        open_writer(tmp_path / "x.mcap", fmt="hdf5")
    with pytest.raises(LogFormatError, match=r"'x\.txt'"):
        open_writer(tmp_path / "x.txt")


def _yuv411_raw(topic: str) -> RawMessage:
    types = ros2_typestore().types
    msg = types["sensor_msgs/msg/Image"](
        header=types["std_msgs/msg/Header"](
            stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="cam"
        ),
        height=2, width=2, encoding="yuv411", is_bigendian=0, step=4,
        data=np.arange(8, dtype=np.uint8),
    )
    data = bytes(ros2_typestore().serialize_cdr(msg, "sensor_msgs/msg/Image"))
    return RawMessage(topic, "sensor_msgs/msg/Image", 1_000_000_000, data, CDR)


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_unsupported_encoding_names_log_and_topic(
    fmt: str, log_path: Callable[[str], Path]
) -> None:
    path = log_path(fmt)
    with open_writer(path, fmt=fmt) as writer:
        writer.write_raw(_yuv411_raw("/cam/yuv"))
    with open_reader(path) as reader:
        (raw,) = reader.raw_messages()
        words = r"topic /cam/yuv: unsupported image encoding 'yuv411'"
        with pytest.raises(EncodingError, match=words) as err:
            reader.decode(raw)
        assert str(path) in str(err.value)
        with pytest.raises(EncodingError, match="/cam/yuv"):
            list(reader.messages())


def interleaved_entries(count: int = 10) -> tuple[list[Entry], list[Entry]]:
    """Two topics with alternating stamps: ``/a`` at even, ``/b`` at odd milliseconds."""
    a = [("/a", T0_NS + 2 * i * 1_000_000, PointStamped(T0_NS + 2 * i * 1_000_000, "w", [i, 0, 0]))
         for i in range(count)]
    b = [("/b", T0_NS + (2 * i + 1) * 1_000_000,
          PointStamped(T0_NS + (2 * i + 1) * 1_000_000, "w", [0, i, 0])) for i in range(count)]
    return a, b


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_messages_come_out_in_log_time_order(fmt: str, log_path: Callable[[str], Path]) -> None:
    a, b = interleaved_entries()
    path = log_path(fmt)
    write_log(path, a + b, fmt=fmt)  # all of /a, then all of /b
    assert read_log(path) == sorted(a + b, key=lambda entry: entry[1])


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_topic_and_time_filters(fmt: str, log_path: Callable[[str], Path]) -> None:
    a, b = interleaved_entries()
    path = log_path(fmt)
    write_log(path, b + a, fmt=fmt)
    every = sorted(a + b, key=lambda entry: entry[1])
    start_ns, end_ns = every[3][1], every[9][1]
    assert read_log(path, topics=["/b"]) == b
    assert read_log(path, topics=["/missing"]) == []
    # half-open range: start included, end excluded
    assert read_log(path, start_ns=start_ns, end_ns=end_ns) == every[3:9]
    assert read_log(path, start_ns=every[-1][1]) == every[-1:]
    assert read_log(path, end_ns=every[0][1]) == []
    assert read_log(path, topics=["/a"], start_ns=start_ns, end_ns=end_ns) == [
        entry for entry in every[3:9] if entry[0] == "/a"
    ]


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_raising_inside_writer_leaves_nothing(fmt: str, log_path: Callable[[str], Path]) -> None:
    path = log_path(fmt)
    with pytest.raises(RuntimeError, match="boom"), open_writer(path, fmt=fmt) as writer:
        writer.write("/text", Text("half"), log_time_ns=1)
        assert writer.temp_path.exists() and not path.exists()
        raise RuntimeError("boom")
    assert list(path.parent.iterdir()) == []


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_existing_output_needs_overwrite(fmt: str, log_path: Callable[[str], Path]) -> None:
    path = log_path(fmt)
    write_log(path, [("/text", 1, Text("first"))], fmt=fmt)
    with pytest.raises(OutputError, match=f"{path} exists"):
        open_writer(path, fmt=fmt)
    assert read_log(path) == [("/text", 1, Text("first"))]
    second = [("/text", 2, Text("second")), ("/text", 3, Text("third"))]
    write_log(path, second, fmt=fmt, overwrite=True)
    assert read_log(path) == second
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_unwritable_destination(fmt: str, tmp_path: Path) -> None:
    missing = tmp_path / "missing" / "log"
    with pytest.raises(OutputError, match="does not exist"):
        open_writer(missing, fmt=fmt)
    not_a_dir = tmp_path / "file.txt"
    not_a_dir.write_text("x")
    with pytest.raises(OutputError, match=str(not_a_dir)):
        open_writer(not_a_dir / "log", fmt=fmt)


def test_writer_rejects_second_type_on_a_topic(tmp_path: Path) -> None:
    with (
        pytest.raises(LogWriteError, match="topic /x has type std_msgs/msg/String"),
        open_writer(tmp_path / "t.mcap") as writer,
    ):
        writer.write("/x", Text("a"), log_time_ns=1)
        writer.write("/x", Image(2, "cam", "mono8", random_pixels("mono8")))
    assert not (tmp_path / "t.mcap").exists()


def test_text_needs_explicit_log_time(tmp_path: Path) -> None:
    with pytest.raises(LogWriteError, match="Text needs log_time_ns"), open_writer(
        tmp_path / "t.mcap"
    ) as writer:
        writer.write("/x", Text("a"))


@pytest.mark.parametrize(
    ("make", "error", "words"),
    [
        (lambda p: p / "nothing.mcap", LogReadError, "does not exist"),
        (lambda p: _file(p / "empty.mcap", b""), LogReadError, "is empty"),
        (lambda p: _file(p / "noise.mcap", _noise()), LogFormatError, "is not a log"),
        (lambda p: _file(p / "noise.bag", _noise()), LogFormatError, "is not a log"),
        (lambda p: _file(p / "magic.mcap", b"\x89MCAP0\r\n" + _noise()), LogReadError, "corrupt"),
        (lambda p: _file(p / "magic.bag", b"#ROSBAG V2.0\n" + _noise()), LogReadError,
         "corrupt"),
        (lambda p: _dir(p / "bare"), LogFormatError, "without rosbag2 metadata.yaml"),
        (lambda p: _file(_dir(p / "bad") / "metadata.yaml", b"x: [").parent, LogReadError,
         "cannot read"),
    ],
    ids=["missing", "empty", "noise", "noise-bag", "mcap-magic-noise", "bag-magic-noise",
         "dir-without-metadata", "bad-metadata"],
)
def test_open_errors_name_the_path(
    tmp_path: Path, make: Callable[[Path], Path], error: type[Exception], words: str
) -> None:
    path = make(tmp_path)
    with pytest.raises(error, match=words) as raised:
        open_reader(path)
    assert str(path) in str(raised.value)
    assert "\n" not in str(raised.value)


def test_rosbag2_directory_without_metadata_reads_its_mcap_storage(tmp_path: Path) -> None:
    """A rosbag2 recording cut short has its MCAP storage file but no metadata.yaml (a
    camlog's temporary output keeps it one folder down)."""
    temp = tmp_path / ".rec.camlog-0123456789abcdef.tmp"
    write_log(_dir(_dir(temp) / "rec") / "rec.mcap", [("/text", 1, Text("x"))])
    for path in (temp, temp / "rec"):
        with open_reader(path) as reader:
            assert [r.message for r in reader.messages()] == [Text("x")]
            assert any("has no metadata.yaml" in w and str(path) in w for w in reader.warnings)


def _without_index(bag: bytes) -> bytes:
    """A ROS1 bag as a killed recording leaves it: header index_pos 0, no index at the end."""
    field = bag.index(b"index_pos=") + len(b"index_pos=")
    index_pos = int.from_bytes(bag[field:field + 8], "little")
    assert 0 < index_pos < len(bag)
    return bag[:field] + bytes(8) + bag[field + 8:index_pos]


def test_ros1_bag_without_index_is_read_from_its_chunks(tmp_path: Path) -> None:
    entries: list[Entry] = [
        ("/cam/image_raw", T0_NS + i, Image(T0_NS + i, "cam", "rgb8",
                                            random_pixels("rgb8", height=240, width=320, seed=i)))
        for i in range(12)  # 2.8 MB: three 1 MiB chunks
    ]
    complete = tmp_path / "complete.bag"
    write_log(complete, entries)
    cut = _file(tmp_path / ".cut.bag.camlog-0123456789abcdef.tmp",
                _without_index(complete.read_bytes()))
    with open_reader(cut) as reader:
        assert "temporary output for cut.bag" in reader.warnings[0]
        assert "has no index" in reader.warnings[1] and "12 messages" in reader.warnings[1]
        read = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
    assert read == read_log(complete)
    assert cut.read_bytes() == _without_index(complete.read_bytes())  # input untouched
    # cut inside the last chunk: the complete chunks before it are read
    torn = _file(tmp_path / "torn.bag", cut.read_bytes()[:-1000])
    with open_reader(torn) as reader:
        partial = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
        assert f"of {torn.stat().st_size}" in reader.warnings[0]
    assert 0 < len(partial) < len(entries)
    assert partial == read[:len(partial)]


def test_rosbag2_storage_file_opens_its_directory(tmp_path: Path) -> None:
    path = tmp_path / "bag"
    write_log(path, [("/text", 5, Text("x"))], fmt="rosbag2-sqlite3")
    (db3,) = path.glob("*.db3")
    assert detect_format(db3) == "rosbag2"
    with open_reader(db3) as reader:
        assert reader.path == path
        assert [r.message for r in reader.messages()] == [Text("x")]


def _noise() -> bytes:
    return np.random.default_rng(1).integers(0, 256, 4096, dtype=np.uint8).tobytes()


def _file(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _dir(path: Path) -> Path:
    path.mkdir()
    return path


@pytest.mark.realdata
def test_real_t265_ros1_bag(realdata_dir: Path) -> None:
    path = realdata_dir / "t265_ros1_bag" / "trimmed_locoffice.bag"
    if not path.is_file():
        pytest.skip(f"real data not found at {path} (set CAMLOG_REALDATA to its folder)")
    from rosbags.highlevel import AnyReader

    topic = "/camera/fisheye1/image_raw"
    with open_reader(path) as reader:
        assert reader.format_name == "ros1"
        assert reader.message_count == 50
        assert reader.topics[topic].msgtype == "sensor_msgs/msg/Image"
        assert reader.topics[topic].count == 3
        images = [record.message for record in reader.messages([topic])]
    # independent decode through rosbags' own reader and ROS1 definitions
    with AnyReader([path]) as anyreader:
        conns = [c for c in anyreader.connections if c.topic == topic]
        expected = [anyreader.deserialize(raw, conn.msgtype)
                    for conn, _, raw in anyreader.messages(connections=conns)]
    assert len(images) == len(expected) == 3
    for image, msg in zip(images, expected, strict=True):
        assert isinstance(image, Image)
        assert (image.encoding, image.width, image.height) == ("mono8", 848, 800)
        assert image.frame_id == "camera_fisheye1_optical_frame"
        assert image.stamp_ns == msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        assert np.array_equal(image.pixels, np.asarray(msg.data).reshape(800, 848))
        assert 10 < image.pixels.mean() < 245  # a real picture, not a blank buffer


def test_overwrite_refuses_a_directory_that_is_not_a_log(tmp_path: Path) -> None:
    precious = tmp_path / "home"
    precious.mkdir()
    (precious / "notes.txt").write_text("keep me")
    with pytest.raises(OutputError, match="not a rosbag2 log"):
        open_writer(precious, fmt="rosbag2", overwrite=True)
    assert (precious / "notes.txt").read_text() == "keep me"


def test_overwrite_replaces_a_log_of_the_other_kind(tmp_path: Path) -> None:
    target = tmp_path / "run"
    target.write_bytes(b"old file")
    with open_writer(target, fmt="rosbag2", overwrite=True) as writer:
        writer.write("/t", Text("x"), log_time_ns=1)
    assert (target / "metadata.yaml").is_file()
    with open_writer(target, fmt="mcap", overwrite=True) as writer:
        writer.write("/t", Text("y"), log_time_ns=2)
    assert target.is_file()
    with open_reader(target) as reader:
        assert [r.message for r in reader.messages()] == [Text("y")]


def test_parent_that_is_a_file_is_named(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(OutputError, match="is not a directory"):
        open_writer(blocker / "out.mcap")


@pytest.mark.parametrize("fmt", ["jpeg", "png"])
def test_frames_decodes_compressed_topics_on_read(tmp_path: Path, fmt: str) -> None:
    from replay.frames import decode_frame, encode_compressed

    ys, xs = np.mgrid[0:24, 0:32]
    flat = np.stack([xs * 7, ys * 9, 255 - xs * 5], axis=-1).astype(np.uint8)
    raw = Image(T0_NS, "cam", "rgb8", flat)
    path = tmp_path / "c.mcap"
    with open_writer(path) as writer:
        writer.write("/cam/image_raw", raw)
        writer.write("/cam/image_raw/compressed", encode_compressed(decode_frame(raw), fmt))
        writer.write("/cam/label", Text("not an image"), log_time_ns=T0_NS)
    with open_reader(path) as reader:
        records = list(reader.frames())
        assert {r.topic for r in records} == {"/cam/image_raw", "/cam/image_raw/compressed"}
        decoded = next(r.message for r in records if r.topic.endswith("compressed"))
        assert decoded.source == fmt and decoded.stamp_ns == T0_NS
        error = np.abs(decoded.rgb8().astype(int) - flat.astype(int))
        assert error.max() == 0 if fmt == "png" else error.mean() < 8
        with pytest.raises(TopicError, match="/cam/label"):
            list(reader.frames(["/cam/label"]))
