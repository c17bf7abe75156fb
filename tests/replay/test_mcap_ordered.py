"""MCAP messages read chunk by chunk give the mcap library's log-time order."""

from __future__ import annotations

import random
from pathlib import Path

import pytest
from mcap.reader import SeekingReader
from mcap.writer import CompressionType, IndexType, Writer

from replay import LogReadError, open_reader
from replay.formats.mcap.ordered import ordered_chunks


def write_mcap(path: Path, *, overlap: bool, compression: CompressionType) -> None:
    """Three topics in chunks of 12 messages whose times go back inside a chunk and may tie
    with the previous chunk's last; with ``overlap`` one chunk starts before the previous
    one ends."""
    rng = random.Random(5)
    with path.open("wb") as f:
        writer = Writer(f, chunk_size=1 << 20, compression=compression)
        writer.start(profile="ros2", library="test")
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channels = [writer.register_channel(t, "cdr", schema) for t in ("/a", "/b", "/c")]
        last = 1_000_000
        for chunk in range(60):
            first = last - 50 if overlap and chunk == 30 else last + rng.choice([0, 0, 7])
            stamps = [first, *(first + rng.randint(0, 200) for _ in range(11))]
            rng.shuffle(stamps)
            for index, stamp in enumerate(stamps):
                data = b"\x00\x01\x00\x00" + rng.randbytes(rng.randint(0, 300))
                writer.add_message(rng.choice(channels), stamp, data, stamp, index)
            writer.flush()
            last = max(stamps)
        writer.finish()


def library_order(path: Path, topics: list[str] | None, start: int | None,
                  end: int | None) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as f:
        reader = SeekingReader(f, validate_crcs=True)
        return [(c.topic, m.log_time, m.data) for _, c, m in reader.iter_messages(
            topics=topics, log_time_order=True, starting_at=start, ending_before=end)]


@pytest.mark.parametrize("compression", [CompressionType.ZSTD, CompressionType.LZ4,
                                         CompressionType.NONE])
@pytest.mark.parametrize("overlap", [False, True])
def test_same_order_as_the_mcap_reader(tmp_path: Path, compression: CompressionType,
                                       overlap: bool) -> None:
    path = tmp_path / "log.mcap"
    write_mcap(path, overlap=overlap, compression=compression)
    with path.open("rb") as f:
        summary = SeekingReader(f).get_summary()
        chunks = ordered_chunks(summary)
        assert len(summary.chunk_indexes) > 20
    assert (chunks is None) == overlap  # overlapping chunks go through the library's queue
    for topics, start, end in [(None, None, None), (["/b", "/c"], None, None),
                               (None, 1_002_000, 1_004_000), (["/a"], 1_001_000, None)]:
        with open_reader(path) as reader:
            ours = [(r.topic, r.log_time_ns, bytes(r.data))
                    for r in reader.raw_messages(topics, start, end)]
        assert ours == library_order(path, topics, start, end)
        assert ours


def test_a_damaged_chunk_is_one_error(tmp_path: Path) -> None:
    path = tmp_path / "log.mcap"
    write_mcap(path, overlap=False, compression=CompressionType.NONE)
    with path.open("rb") as f:
        summary = SeekingReader(f).get_summary()
    middle = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[10]
    data = bytearray(path.read_bytes())
    at = middle.chunk_start_offset + middle.chunk_length - 20
    data[at:at + 4] = bytes(4 * [0xFF])  # inside its records: the CRC no longer holds
    path.write_bytes(bytes(data))
    with open_reader(path) as reader, pytest.raises(LogReadError, match="corrupt"):
        list(reader.raw_messages())


@pytest.mark.parametrize("layout", ["unchunked", "no message indexes"])
def test_files_without_chunk_or_message_indexes_read_as_the_mcap_reader(
        tmp_path: Path, layout: str) -> None:
    """A summary that indexes no chunk (messages outside chunks) or chunks without message
    indexes (topic membership unknown until read): nothing may be skipped."""
    path = tmp_path / "log.mcap"
    with path.open("wb") as f:
        writer = Writer(f, chunk_size=2048, use_chunking=layout != "unchunked",
                        index_types=IndexType.ALL & ~IndexType.MESSAGE)
        writer.start(profile="ros2", library="test")
        schema = writer.register_schema("std_msgs/msg/String", "ros2msg", b"string data")
        channels = [writer.register_channel(t, "cdr", schema) for t in ("/a", "/b")]
        for i in range(200):
            writer.add_message(channels[i % 2], 1000 + i, b"\x00\x01\x00\x00" + bytes(40), 0, i)
        writer.finish()
    for topics in (None, ["/b"]):
        with open_reader(path) as reader:
            ours = [(r.topic, r.log_time_ns, bytes(r.data)) for r in reader.raw_messages(topics)]
        assert ours == library_order(path, topics, None, None)
        assert len(ours) == (200 if topics is None else 100)
