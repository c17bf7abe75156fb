"""MCAP specifics: chunk ordering, crash safety, truncation, corruption, bounded memory."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from replay import Image, LogReadError, PointStamped, Text, open_reader, open_writer
from tests.outputs import temp_outputs

from .samples import T0_NS, Entry, read_log, write_log


def numbered_images(count: int, *, height: int = 60, width: int = 80) -> list[Entry]:
    """``/cam/image`` frames whose pixels are reproducible from their index."""
    entries: list[Entry] = []
    for index in range(count):
        stamp_ns = T0_NS + index * 33_000_000
        pixels = np.random.default_rng(index).integers(0, 256, (height, width), dtype=np.uint8)
        entries.append(("/cam/image", stamp_ns, Image(stamp_ns, "cam", "mono8", pixels)))
    return entries


def chunk_starts(path: Path) -> list[tuple[int, int, int]]:
    """``(offset, length, first log time)`` of every chunk, in file order."""
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    return sorted((c.chunk_start_offset, c.chunk_length, c.message_start_time)
                  for c in summary.chunk_indexes)


def test_overlapping_chunks_merge_in_log_time_order(tmp_path: Path) -> None:
    a = [("/a", T0_NS + 2 * i, PointStamped(T0_NS + 2 * i, "w", [i, 0, 0])) for i in range(20)]
    b = [("/b", T0_NS + 2 * i + 1, Text(f"b{i}")) for i in range(20)]
    path = tmp_path / "o.mcap"
    write_log(path, a + b, chunk_size=1)  # one chunk per message, /b chunks after all of /a
    assert len(chunk_starts(path)) == 40
    expected = sorted(a + b, key=lambda entry: entry[1])
    assert read_log(path) == expected
    # the summary-less (recovery) path restores the order too
    with open_reader(path, recover=True) as reader:
        assert [(r.topic, r.log_time_ns, r.message) for r in reader.messages()] == expected


def test_metadata_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "m.mcap"
    with open_writer(path) as writer:
        writer.set_metadata("scenario", {"name": "desk", "seed": "7"})
        writer.write("/text", Text("x"), log_time_ns=1)
    with open_reader(path) as reader:
        assert reader.metadata == {"scenario": {"name": "desk", "seed": "7"}}


CHILD = textwrap.dedent(
    """
    # Writes numbered frames until killed; prints "index size" whenever the file grew on
    # disk, i.e. a chunk ending at or before frame `index` was handed to the OS.
    import sys
    import numpy as np
    from replay import Image, open_writer

    writer = open_writer(sys.argv[1], chunk_size=64 * 1024)
    last_size = 0
    for index in range(20_000):
        pixels = np.random.default_rng(index).integers(0, 256, (60, 80), dtype=np.uint8)
        stamp_ns = {t0} + index * 33_000_000
        writer.write("/cam/image", Image(stamp_ns, "cam", "mono8", pixels))
        size = writer.temp_path.stat().st_size
        if size != last_size:
            last_size = size
            print(index, size, flush=True)
    """
).format(t0=T0_NS)


@pytest.mark.slow
def test_killed_writer_leaves_a_readable_partial(tmp_path: Path) -> None:
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    out = tmp_path / "rec.mcap"
    lines: list[str] = []
    with subprocess.Popen(
        [sys.executable, str(script), str(out)], stdout=subprocess.PIPE, text=True
    ) as child:
        assert child.stdout is not None
        try:
            while len(lines) < 4:  # a few (incompressible, so > write buffer) chunks on disk
                line = child.stdout.readline()
                assert line, "writer exited before flushing chunks"
                lines.append(line)
        finally:
            child.send_signal(signal.SIGKILL)
            lines += child.stdout.read().splitlines()
            child.wait()
    assert child.returncode == -signal.SIGKILL
    flushed = max(int(line.split()[0]) for line in lines) + 1
    (partial,) = temp_outputs(tmp_path)
    assert partial.is_file() and not out.exists()

    with open_reader(partial) as reader:
        assert any("incomplete" in warning for warning in reader.warnings), reader.warnings
        recovered = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
        assert reader.message_count == len(recovered)
    # chunks are finished on a worker thread: when the file grew, up to two chunks handed to
    # it (14 frames of 4.8 kB each in 64 KiB) and the open one may not be on disk yet
    assert len(recovered) >= flushed - 3 * 15
    assert recovered == numbered_images(len(recovered))


def test_truncated_copy_yields_a_prefix(tmp_path: Path) -> None:
    entries = numbered_images(40)
    path = tmp_path / "full.mcap"
    write_log(path, entries, chunk_size=20_000)
    data = path.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with open_reader(cut) as reader:
        assert reader.warnings and "incomplete" in reader.warnings[0]
        assert str(cut) in reader.warnings[0]
        got = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
    assert 0 < len(got) < len(entries)
    assert got == entries[: len(got)]


def test_file_cut_inside_its_header_is_empty_not_an_error(tmp_path: Path) -> None:
    path = tmp_path / "full.mcap"
    write_log(path, numbered_images(2))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[:20])
    with open_reader(cut) as reader:
        assert reader.warnings
        assert list(reader.messages()) == []


def _corrupt_middle_chunk(tmp_path: Path) -> tuple[Path, list[Entry], int]:
    entries = numbered_images(40)
    path = tmp_path / "bad.mcap"
    write_log(path, entries, chunk_size=20_000)
    chunks = chunk_starts(path)
    assert len(chunks) >= 4
    offset, length, first_ns = chunks[len(chunks) // 2]
    data = bytearray(path.read_bytes())
    middle = offset + length // 2
    data[middle : middle + 32] = bytes(b ^ 0xFF for b in data[middle : middle + 32])
    path.write_bytes(bytes(data))
    return path, entries, first_ns


def _next_chunk_ns(path: Path, first_ns: int) -> int:
    return min(ns for _, _, ns in chunk_starts(path) if ns > first_ns)


def test_corrupt_chunk_raises(tmp_path: Path) -> None:
    path, _, _ = _corrupt_middle_chunk(tmp_path)
    with (
        pytest.raises(LogReadError, match=r"corrupt .*--recover") as raised,
        open_reader(path) as reader,
    ):
        for _ in reader.messages():
            pass
    assert str(path) in str(raised.value)


def test_recover_skips_the_damaged_chunk_and_reads_on(tmp_path: Path) -> None:
    path, entries, damaged_from_ns = _corrupt_middle_chunk(tmp_path)
    damaged_to_ns = _next_chunk_ns(path, damaged_from_ns)
    lost = [e for e in entries if damaged_from_ns <= e[1] < damaged_to_ns]
    with open_reader(path, recover=True) as reader:
        (warning,) = [w for w in reader.warnings if "skipped the damaged chunk" in w]
        got = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
    assert got == [e for e in entries if e not in lost]
    assert 0 < len(lost) < len(entries) // 2
    assert f"{len(lost)} messages lost, log times {lost[0][1]} to {lost[-1][1]} ns" in warning


def test_a_chunk_written_twice_is_read_once(tmp_path: Path) -> None:
    entries = numbered_images(20)
    path = tmp_path / "twice.mcap"
    write_log(path, entries, chunk_size=20_000)
    chunks = chunk_starts(path)
    assert len(chunks) >= 3
    start, end = chunks[1][0], chunks[2][0]  # a chunk and its message indexes
    data = path.read_bytes()
    path.write_bytes(data[:end] + data[start:end] + data[end:])
    with open_reader(path, recover=True) as reader:
        got = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
        assert any("repeats an earlier one" in w for w in reader.warnings), reader.warnings
    assert got == entries


@pytest.mark.slow
def test_reading_a_long_log_keeps_memory_flat(tmp_path: Path) -> None:
    """300 VGA rgb8 frames (276 MB raw) are read with a few chunks in memory at a time."""
    rng = np.random.default_rng(0)
    base = rng.integers(0, 256, (480, 640, 3), dtype=np.uint8)
    base[:, :, 1:] //= 32  # compressible, so the file stays small and fast to write
    path = tmp_path / "long.mcap"
    with open_writer(path) as writer:
        for index in range(300):
            pixels = np.roll(base, index, axis=1)
            writer.write("/cam/image", Image(T0_NS + index * 33_000_000, "cam", "rgb8", pixels))
    frame_bytes = base.nbytes
    with open_reader(path) as reader:
        tracemalloc.start()
        try:
            count = 0
            checksum = 0
            for record in reader.messages():
                assert isinstance(record.message, Image)
                count += 1
                checksum += int(record.message.pixels[0, count % 640, 0])
            _, peak_bytes = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
    assert count == 300
    assert checksum > 0
    assert peak_bytes > frame_bytes  # decoded frames are traced, so the bound means something
    assert peak_bytes < 30 * 1024 * 1024, f"peak {peak_bytes / 2**20:.1f} MiB"
