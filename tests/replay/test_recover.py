"""--recover past damage in ROS1 bags and rosbag2 folders, and metadata.yaml not believed.

Each damaged log is checked against what an independent reader (``rosbags``, ``sqlite3``,
``mcap``) finds in the intact one: the recovered messages are the intact log's messages but
for the damaged stretch, and the warnings count what was lost.
"""

from __future__ import annotations

import re
import shutil
import sqlite3
import struct
from pathlib import Path

import pytest
from mcap.reader import make_reader
from rosbags.rosbag1 import Reader as Rosbag1Reader

from replay import LogReadError, Text, open_reader

from .fuzz import write_seed
from .samples import T0_NS, write_log


def _messages(path: Path, *, recover: bool) -> tuple[list[tuple[str, int, bytes]], list[str]]:
    with open_reader(path, recover=recover) as reader:
        messages = [(m.topic, m.log_time_ns, bytes(m.data)) for m in reader.raw_messages()]
        return messages, list(reader.warnings)


def _ros1_chunks(data: bytes) -> list[tuple[int, int, int]]:
    """``(offset, header length, data length)`` of a bag's top-level chunk records."""
    chunks, offset = [], 13
    while offset + 4 <= len(data):
        (header,) = struct.unpack_from("<I", data, offset)
        (size,) = struct.unpack_from("<I", data, offset + 4 + header)
        if b"op=\x05" in data[offset + 4:offset + 4 + header]:
            chunks.append((offset, header, size))
        offset += 8 + header + size
    return chunks


def _ros1_originals(path: Path) -> list[tuple[str, int, bytes]]:
    with Rosbag1Reader(path) as reader:
        return [(c.topic, t, d) for c, t, d in reader.messages()]


@pytest.mark.parametrize("damage", ["zeroed data", "huge header length"])
def test_ros1_recover_reads_past_a_damaged_chunk(tmp_path: Path, damage: str) -> None:
    seed = write_seed("ros1", tmp_path)
    data = bytearray(seed.read_bytes())
    chunks = _ros1_chunks(bytes(data))
    assert len(chunks) == 3
    offset, header, size = chunks[1]
    if damage == "zeroed data":
        data[offset + 8 + header:offset + 8 + header + size] = bytes(size)
    else:
        data[offset:offset + 4] = struct.pack("<I", 0x7FFFFFFF)
    damaged = tmp_path / "damaged.bag"
    damaged.write_bytes(bytes(data))
    with pytest.raises(LogReadError, match="--recover"):
        _messages(damaged, recover=False)
    originals = _ros1_originals(seed)
    recovered, warnings = _messages(damaged, recover=True)
    # the middle chunk held the third and fourth frames: 2 images, 2 compressed images
    lost_times = {T0_NS + 3 * 33_000_000, T0_NS + 4 * 33_000_000}
    assert recovered == [m for m in originals if m[1] not in lost_times]
    lost = [w for w in warnings if "skipped bytes" in w]
    assert len(lost) == 1
    assert f"skipped bytes {offset} to" in lost[0]
    assert f"4 messages lost, log times {min(lost_times)} to {max(lost_times)} ns" in lost[0]
    assert damaged.read_bytes() == bytes(data)  # the input is never modified


def test_ros1_recover_of_a_cut_bag_says_from_when_it_lost(tmp_path: Path) -> None:
    seed = write_seed("ros1", tmp_path)
    data = seed.read_bytes()
    offset = _ros1_chunks(data)[2][0]
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[:offset + 40])
    recovered, warnings = _messages(cut, recover=True)
    originals = _ros1_originals(seed)
    assert recovered == originals[:len(recovered)]
    assert len(recovered) == 10
    assert any(f"skipped bytes {offset} to {offset + 40}" in w
               and f"between log times {T0_NS + 4 * 33_000_000} to end" in w for w in warnings)


def _leaf_pages(db3: Path) -> list[int]:
    """Page numbers of a database's table b-tree leaf pages past its first few."""
    data = db3.read_bytes()
    page_size = struct.unpack(">H", data[16:18])[0]
    return [n for n in range(4, len(data) // page_size)
            if data[(n - 1) * page_size] == 0x0D]


def test_rosbag2_sqlite_recover_reads_the_rows_that_read(tmp_path: Path) -> None:
    log = tmp_path / "log"
    entries = [("/text", T0_NS + i, Text(f"{i:04d}" + "x" * 600)) for i in range(300)]
    write_log(log, entries, fmt="rosbag2-sqlite3")
    db3 = next(log.glob("*.db3"))
    connection = sqlite3.connect(db3)
    originals = [t for (t,) in connection.execute("SELECT timestamp FROM messages ORDER BY id")]
    connection.close()
    pages = _leaf_pages(db3)
    page_size = struct.unpack(">H", db3.read_bytes()[16:18])[0]
    data = bytearray(db3.read_bytes())
    data[(pages[len(pages) // 2] - 1) * page_size] = 0x00  # not a page type: malformed
    damaged = tmp_path / "damaged"
    shutil.copytree(log, damaged)
    next(damaged.glob("*.db3")).write_bytes(bytes(data))
    with pytest.raises(LogReadError, match="--recover"):
        _messages(damaged, recover=False)
    recovered, warnings = _messages(damaged, recover=True)
    times = [t for _topic, t, _data in recovered]
    assert 0 < len(times) < len(originals)
    assert set(times) < set(originals)
    assert times == sorted(times)
    (line,) = [w for w in warnings if "do not read" in w]
    lost = int(re.search(r"(\d+) message rows do not read", line).group(1))  # type: ignore[union-attr]
    assert lost + len(times) == len(originals)
    first_lost = min(set(originals) - set(times))
    assert f"between log times {first_lost - 1} to" in line
    assert next(damaged.glob("*.db3")).read_bytes() == bytes(data)


def test_rosbag2_mcap_storage_recover_skips_a_damaged_chunk(tmp_path: Path) -> None:
    seed = write_seed("rosbag2 (mcap)", tmp_path)
    storage = next(seed.glob("*.mcap"))
    with storage.open("rb") as f:
        summary = make_reader(f).get_summary()
        assert summary is not None
        chunk = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)[1]
        originals = [(c.topic, m.log_time, m.data) for _s, c, m in
                     make_reader(f).iter_messages(log_time_order=True)]
    data = bytearray(storage.read_bytes())
    middle = chunk.chunk_start_offset + chunk.chunk_length // 2
    data[middle:middle + 16] = bytes(16)
    storage.write_bytes(bytes(data))
    with pytest.raises(LogReadError, match="--recover"):
        _messages(seed, recover=False)
    recovered, warnings = _messages(seed, recover=True)
    lost = [m for m in originals
            if chunk.message_start_time <= m[1] <= chunk.message_end_time]
    assert recovered == [m for m in originals if m not in lost]
    assert any(f"{len(lost)} messages lost" in w for w in warnings)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rosbag2 (sqlite3)", "rosbag2 (mcap)"])
def test_a_repeated_metadata_line_loses_no_messages(tmp_path: Path, name: str) -> None:
    seed = write_seed(name, tmp_path)
    originals, _warnings = _messages(seed, recover=False)
    lines = (seed / "metadata.yaml").read_text().splitlines(keepends=True)
    for index, line in enumerate(lines):
        copy = tmp_path / f"repeated{index}"
        shutil.copytree(seed, copy)
        repeated = [*lines[:index + 1], line, *lines[index + 1:]]
        (copy / "metadata.yaml").write_text("".join(repeated))
        with open_reader(copy) as reader:
            counts = {topic: info.count for topic, info in reader.topics.items()}
            read = [(m.topic, m.log_time_ns, bytes(m.data)) for m in reader.raw_messages()]
        assert read == originals, line
        assert counts == {"/scenario": 1, "/cam/camera_info": 1, "/cam/image": 6,
                          "/cam/compressed": 6}, line


@pytest.mark.parametrize("name", ["rosbag2 (sqlite3)", "rosbag2 (mcap)"])
def test_a_metadata_count_that_disagrees_is_reported_and_not_believed(
        tmp_path: Path, name: str) -> None:
    seed = write_seed(name, tmp_path)
    metadata = seed / "metadata.yaml"
    metadata.write_text(metadata.read_text().replace("message_count: 6", "message_count: 0", 1))
    with open_reader(seed) as reader:
        assert reader.topics["/cam/image"].count == 6
        assert reader.message_count == 14
        assert any("metadata.yaml counts 0 messages on /cam/image, its storage holds 6" in w
                   for w in reader.warnings)
