"""Crash safety of every writer: a live writer killed mid-way loses at most its last second,
the others give the same bytes for the same messages however slowly they run, the output
carries checksums where the format has them, and asked-for compression is honoured."""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from mcap.reader import make_reader
from mcap.stream_reader import CRCValidationError
from rosbags.rosbag2 import Reader as Rosbags2Reader

from replay import LogWriteError, Text, open_reader, open_writer
from replay.formats import base as formats_base
from replay.formats.base import FLUSH_INTERVAL_S

from .samples import OUTPUT_NAMES, T0_NS, WRITE_FORMATS, read_log, write_log
from .test_mcap import numbered_images

CHILD = textwrap.dedent(
    """
    # Writes numbered frames every 10 ms until killed and prints each index once written.
    import sys, time
    import numpy as np
    from replay import Image, open_writer

    writer = open_writer(sys.argv[1], fmt=sys.argv[2], live=True)
    for index in range(100_000):
        pixels = np.random.default_rng(index).integers(0, 256, (60, 80), dtype=np.uint8)
        stamp_ns = {t0} + index * 33_000_000
        writer.write("/cam/image", Image(stamp_ns, "cam", "mono8", pixels))
        print(index, flush=True)
        time.sleep(0.01)
    """
).format(t0=T0_NS)


def only_entry(folder: Path) -> Path:
    """The one file or folder a killed writer left in ``folder`` (its temporary output)."""
    entries = list(folder.iterdir())
    assert len(entries) == 1, entries
    return entries[0]


@pytest.mark.slow
@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_killed_writer_keeps_all_but_the_last_second(tmp_path: Path, fmt: str) -> None:
    assert FLUSH_INTERVAL_S <= 0.5  # leaves half a second for the writer to get there
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    out = tmp_path / "out"
    out.mkdir()
    written: list[tuple[float, int]] = []  # (when the parent saw it, index)
    with subprocess.Popen([sys.executable, str(script), str(out / OUTPUT_NAMES[fmt]), fmt],
                          stdout=subprocess.PIPE, text=True) as child:
        assert child.stdout is not None
        try:
            while not written or written[-1][0] - written[0][0] < 2.5:
                line = child.stdout.readline()
                assert line, "the writer exited"
                written.append((time.monotonic(), int(line)))
        finally:
            child.send_signal(signal.SIGKILL)
            killed_at = time.monotonic()
            child.wait()
    assert child.returncode == -signal.SIGKILL
    durable = max(i for seen, i in written if seen <= killed_at - 1.0) + 1
    with open_reader(only_entry(out)) as reader:
        assert reader.warnings  # it says the log is incomplete
        recovered = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
    assert len(recovered) >= durable
    assert recovered == numbered_images(len(recovered))


@pytest.mark.slow
def test_sqlite_recording_killed_mid_transaction_reads_its_commits(tmp_path: Path) -> None:
    """The killed writer leaves a hot journal: the reader rolls back a copy, never the input."""
    script = tmp_path / "child.py"
    script.write_text(textwrap.dedent(
        """
        import os, signal, sys
        import numpy as np
        from replay import Image, open_writer

        writer = open_writer(sys.argv[1], fmt="rosbag2-sqlite3")
        for index in range(40):
            pixels = np.random.default_rng(index).integers(0, 256, (480, 640), dtype=np.uint8)
            writer.write("/cam/image", Image(index + 1, "cam", "mono8", pixels))
            if index == 19:
                writer.flush()  # 20 committed; the next 20 (6 MB) spill into the file
        os.kill(os.getpid(), signal.SIGKILL)
        """))
    out = tmp_path / "out"
    out.mkdir()
    result = subprocess.run([sys.executable, str(script), str(out / "bag")], check=False)
    assert result.returncode == -signal.SIGKILL
    partial = only_entry(out)
    journals = list(partial.rglob("*.db3-journal"))
    assert journals, "expected a hot journal"
    before = {p: p.read_bytes() for p in partial.rglob("*") if p.is_file()}
    with open_reader(partial) as reader:
        (reindexed,) = [w for w in reader.warnings if "ros2 bag reindex" in w]
        assert "20 messages" in reindexed
        stamps = [r.log_time_ns for r in reader.raw_messages()]
    assert stamps == list(range(1, 21))
    assert {p: p.read_bytes() for p in partial.rglob("*") if p.is_file()} == before


@pytest.mark.parametrize("compression", ["none", "zstd"])
def test_sqlite_directory_without_metadata_is_read_like_reindex(
    tmp_path: Path, compression: str
) -> None:
    entries = numbered_images(5)
    write_log(tmp_path / "bag", entries, fmt="rosbag2-sqlite3", compression=compression)
    (tmp_path / "bag" / "metadata.yaml").unlink()
    with open_reader(tmp_path / "bag") as reader:
        assert reader.format_name == "rosbag2 (sqlite3)"
        assert "has no metadata.yaml" in reader.warnings[0]
        assert reader.topics["/cam/image"].count == 5
        got = [(r.topic, r.log_time_ns, r.message) for r in reader.messages()]
    assert got == entries


@pytest.mark.parametrize("fmt", ["mcap", "rosbag2"])
def test_mcap_chunks_carry_crcs_that_catch_damage(tmp_path: Path, fmt: str) -> None:
    path = tmp_path / OUTPUT_NAMES[fmt]
    write_log(path, numbered_images(40), fmt=fmt, compression="none")
    storage = path if fmt == "mcap" else path / "log.mcap"
    with storage.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.chunk_indexes
    data = bytearray(storage.read_bytes())
    for index in summary.chunk_indexes:  # the record's uncompressed_crc field is set
        crc_at = index.chunk_start_offset + 1 + 8 + 8 + 8 + 8
        assert int.from_bytes(data[crc_at:crc_at + 4], "little") != 0
    # one flipped byte inside the first chunk's messages: independent readers notice
    first = summary.chunk_indexes[0]
    data[first.chunk_start_offset + first.chunk_length - 100] ^= 0xFF
    storage.write_bytes(bytes(data))
    with storage.open("rb") as f, pytest.raises(CRCValidationError):
        list(make_reader(f, validate_crcs=True).iter_messages())
    if fmt == "rosbag2":
        with Rosbags2Reader(path) as bag, pytest.raises(Exception, match="checksum"):
            list(bag.messages())


def test_rosbag2_compression_is_honoured(tmp_path: Path) -> None:
    entries = [("/text", T0_NS + i, Text("camlog " * 2000)) for i in range(50)]
    sizes = {}
    for storage, compression in [("rosbag2", "none"), ("rosbag2", "zstd"),
                                 ("rosbag2-sqlite3", "none"), ("rosbag2-sqlite3", "zstd")]:
        path = tmp_path / f"{storage}-{compression}"
        with open_writer(path, fmt=storage, compression=compression) as writer:
            for topic, log_time_ns, message in entries:
                writer.write(topic, message, log_time_ns=log_time_ns)
        sizes[storage, compression] = sum(p.stat().st_size for p in path.iterdir())
        assert read_log(path) == entries
        with Rosbags2Reader(path) as bag:  # independent reader
            assert bag.message_count == 50
            mode = bag.compression_mode or None
        assert mode == ("message" if (storage, compression) == ("rosbag2-sqlite3", "zstd")
                        else None)
    mcap_storage = tmp_path / "rosbag2-zstd" / "rosbag2-zstd.mcap"
    with mcap_storage.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    assert {c.compression for c in summary.chunk_indexes} == {"zstd"}
    for storage in ("rosbag2", "rosbag2-sqlite3"):
        assert sizes[storage, "zstd"] * 20 < sizes[storage, "none"], sizes


@pytest.mark.parametrize(("fmt", "compression"), [("rosbag2", "lz4"), ("rosbag2-sqlite3", "lz4"),
                                                  ("ros1", "zstd"), ("mcap", "bz2")])
def test_unsupported_compression_is_one_line_and_writes_nothing(
    tmp_path: Path, fmt: str, compression: str
) -> None:
    with pytest.raises(LogWriteError, match=f"'{compression}' compression") as raised:
        open_writer(tmp_path / OUTPUT_NAMES[fmt], fmt=fmt, compression=compression)
    assert "\n" not in str(raised.value)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_disk_errors_name_the_output_and_leave_nothing(tmp_path: Path) -> None:
    """A write the OS refuses (here: beyond RLIMIT_FSIZE, EFBIG) is one error naming the
    output, and the temporary output is gone."""
    script = tmp_path / "child.py"
    script.write_text(textwrap.dedent(
        """
        import resource, sys
        import numpy as np
        from replay import Image, ReplayError, open_writer

        resource.setrlimit(resource.RLIMIT_FSIZE, (2_000_000, 2_000_000))
        try:
            with open_writer(sys.argv[1], fmt=sys.argv[2], compression="none") as writer:
                for index in range(100):
                    pixels = np.zeros((480, 640), dtype=np.uint8)
                    writer.write("/cam/image", Image(index + 1, "cam", "mono8", pixels))
        except ReplayError as err:
            print(f"{type(err).__name__}: {err}")
        """))
    for fmt in WRITE_FORMATS:
        out = tmp_path / fmt
        out.mkdir()
        target = out / OUTPUT_NAMES[fmt]
        result = subprocess.run([sys.executable, str(script), str(target), fmt],
                                capture_output=True, text=True, check=False)
        assert result.returncode == 0, result.stderr
        assert result.stdout.startswith(f"LogWriteError: cannot write {target}: "), result.stdout
        assert result.stdout.count("\n") == 1
        assert list(out.iterdir()) == [], fmt
        shutil.rmtree(out)


def _files(output: Path) -> dict[str, bytes]:
    """The bytes of a log file, or of each file in a rosbag2 folder."""
    if output.is_file():
        return {output.name: output.read_bytes()}
    return {p.name: p.read_bytes() for p in sorted(output.iterdir())}


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
def test_the_same_messages_give_the_same_bytes_however_slow_the_writer(
        tmp_path: Path, fmt: str, monkeypatch: pytest.MonkeyPatch) -> None:
    entries = numbered_images(30)

    def write(folder: str, *, live: bool = False) -> dict[str, bytes]:
        (tmp_path / folder).mkdir()
        path = tmp_path / folder / OUTPUT_NAMES[fmt]
        with open_writer(path, fmt=fmt, live=live) as writer:
            for topic, log_time_ns, message in entries:
                writer.write(topic, message, log_time_ns=log_time_ns)
        return _files(path)

    steady = write("steady")
    ticks = iter(range(10**6))  # every reading of the clock a second after the last
    monkeypatch.setattr(formats_base, "time", SimpleNamespace(monotonic=lambda: next(ticks)))
    assert write("slow") == steady
    assert write("slow_live", live=True) != steady  # a live writer completes more chunks
