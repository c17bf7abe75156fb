"""MCAP chunks finished on a worker thread: the same bytes as the mcap library's writer,
valid for independent readers, and a failed write reported as one error."""

from __future__ import annotations

import errno
import io
import random
import threading
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import SeekingReader
from mcap.writer import CompressionType, Writer
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from camlog.logs.convert import convert_log
from camlog.requests.logs import ConvertRequest
from replay import LogWriteError, open_reader
from replay.formats.base import RawMessage
from replay.formats.chunk_worker import OrderedWorker
from replay.formats.mcap.chunks import McapChunkWriter
from replay.formats.mcap.writer import McapLogWriter
from replay.formats.rosbag2.storage_plugins import McapStorage
from tests.recordings import chunked_camera_log

COMPRESSIONS = [(CompressionType.ZSTD, "zstd"), (CompressionType.LZ4, "lz4"),
                (CompressionType.NONE, "")]


def write_sample(writer: Any, *, messages: int = 1500, seed: int = 1) -> list[tuple[int, int]]:
    """Schemas and channels registered before and between messages, metadata, a flush, log
    times that sometimes go back; the (channel, log time) of every message written."""
    rng = random.Random(seed)
    writer.start(profile="ros2", library="test")
    first = writer.register_channel("/a", "cdr", writer.register_schema(
        "pkg/msg/A", "ros2msg", b"int32 x"), {"offered_qos_profiles": "- depth: 1"})
    writer.add_metadata("before", {"key": "value"})
    second = 0
    written = []
    log_time = 1_000
    for index in range(messages):
        if index == messages // 3:
            second = writer.register_channel("/b", "cdr", writer.register_schema(
                "pkg/msg/B", "ros2msg", b"uint8 y"))
        channel = first if not second or rng.random() < 0.5 else second
        log_time += rng.randint(-5, 50)
        data = rng.randbytes(rng.randint(0, 3000))
        writer.add_message(channel, log_time, data, log_time + 1, index)
        written.append((channel, log_time))
        if index == messages // 2:
            writer.flush()
    writer.add_metadata("after", {"a": "b"})
    writer.finish()
    return written


@pytest.mark.parametrize(("library", "name"), COMPRESSIONS)
def test_same_bytes_as_the_mcap_writer(library: CompressionType, name: str) -> None:
    theirs, ours = io.BytesIO(), io.BytesIO()
    write_sample(Writer(theirs, chunk_size=32 * 1024, compression=library))
    write_sample(McapChunkWriter(ours, chunk_size=32 * 1024, compression=name))
    assert len(ours.getvalue()) > 40 * 32 * 1024  # many chunks, each finished by the worker
    assert ours.getvalue() == theirs.getvalue()


def test_chunks_indexes_and_crcs_read_back_in_order() -> None:
    out = io.BytesIO()
    written = write_sample(McapChunkWriter(out, chunk_size=16 * 1024), messages=3000, seed=2)
    out.seek(0)
    reader = SeekingReader(out, validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.message_count == len(written)
    assert summary.statistics.chunk_count == len(summary.chunk_indexes) > 50
    for index in summary.chunk_indexes:  # every offset points at its record
        out.seek(index.chunk_start_offset)
        assert out.read(1) == b"\x06"
        for offset in index.message_index_offsets.values():
            out.seek(offset)
            assert out.read(1) == b"\x07"
    in_file_order = [(m.channel_id, m.log_time)
                     for _, _, m in reader.iter_messages(log_time_order=False)]
    assert in_file_order == written
    in_time = [m.log_time for _, _, m in reader.iter_messages(log_time_order=True)]
    assert in_time == sorted(t for _, t in written)
    assert [m.name for m in reader.iter_metadata()] == ["before", "after"]


@pytest.mark.slow
@pytest.mark.parametrize(("name", "fast", "small"), [("zstd", 1, 19), ("lz4", 0, 12)])
def test_a_compression_level_changes_the_chunks_not_the_messages(tmp_path: Path, name: str,
                                                                 fast: int, small: int) -> None:
    rng = random.Random(3)
    # text-like payloads: every level compresses them, a higher one more tightly
    payloads = [" ".join(rng.choice(["left", "right", "corner", "board", "view", str(i)])
                         for _ in range(400)).encode() for i in range(300)]
    sizes = {}
    for level in (fast, small):
        path = tmp_path / f"{name}_{level}.mcap"
        writer = McapLogWriter(path, compression=name, compression_level=level,
                               chunk_size=64 * 1024)
        for index, data in enumerate(payloads):
            writer.write_raw(RawMessage(topic="/text", msgtype="std_msgs/msg/String",
                                        log_time_ns=1_000 + index, data=data,
                                        serialization="cdr"))
        writer.close()
        sizes[level] = path.stat().st_size
        with path.open("rb") as file:
            reader = SeekingReader(file, validate_crcs=True)
            assert [bytes(m.data) for _, _, m in reader.iter_messages()] == payloads
    assert sizes[small] < 0.95 * sizes[fast]


def test_worker_runs_jobs_in_order_and_reports_a_failure() -> None:
    worker = OrderedWorker(depth=1)
    done: list[int] = []
    threads = set()

    def job(n: int) -> None:
        threads.add(threading.current_thread().name)
        if n == 5:
            raise OSError(errno.ENOSPC, "No space left on device")
        done.append(n)

    with pytest.raises(OSError, match="No space"):
        for n in range(20):
            worker.submit(lambda n=n: job(n))
        worker.drain()
    with pytest.raises(OSError, match="No space"):  # until the writer is abandoned
        worker.drain()
    worker.abort()
    assert done == [0, 1, 2, 3, 4]  # nothing after the failed job
    assert threads == {"camlog-chunks"}
    assert not [t for t in threading.enumerate() if t.name == "camlog-chunks"]


class FullDisk(io.RawIOBase):
    """A file that takes ``room`` bytes, then fails as a full disk does."""

    def __init__(self, room: int) -> None:
        self.room = room

    def writable(self) -> bool:
        return True

    def write(self, data: Any) -> int:
        size = len(memoryview(data))
        if size > self.room:
            raise OSError(errno.ENOSPC, "No space left on device")
        self.room -= size
        return size


def test_a_failed_chunk_write_is_one_error_and_no_output(tmp_path: Path) -> None:
    path = tmp_path / "out.mcap"
    stamps = range(1_700_000_000_000_000_000, 1_700_000_000_000_000_000 + 400 * 1000, 1000)
    with pytest.raises(LogWriteError, match=r"cannot write .*out\.mcap: No space left"), \
            McapLogWriter(path, chunk_size=4096, compression="none") as writer:
        writer._file.close()
        writer._file = writer._writer._file = FullDisk(room=50_000)  # type: ignore[assignment]
        from replay.formats.base import RawMessage

        for stamp in stamps:
            writer.write_raw(RawMessage("/t", "std_msgs/msg/String", stamp,
                                        b"\x00\x01\x00\x00" + bytes(1000), "cdr"))
    assert list(tmp_path.iterdir()) == []  # the temporary output is gone too
    assert not [t for t in threading.enumerate() if t.name.startswith("camlog-chunks")]


def test_ros1_to_rosbag2_in_many_chunks_reads_back(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    source = tmp_path / "cam.mcap"
    stamps = chunked_camera_log(source, frames=60)
    bag = tmp_path / "cam.bag"
    convert_log(ConvertRequest(input=source, output=bag, progress=False))
    monkeypatch.setattr(McapStorage, "CHUNK_SIZE", 8 * 1024)  # a chunk per image or two
    out = tmp_path / "cam_r2"
    convert_log(ConvertRequest(input=bag, output=out, progress=False))
    with (out / "cam_r2.mcap").open("rb") as f:
        reader = SeekingReader(f, validate_crcs=True)
        summary = reader.get_summary()
        assert summary is not None and len(summary.chunk_indexes) >= 25
        times = [(c.topic, m.log_time) for _, c, m in reader.iter_messages()]
    assert [t for topic, t in times if topic == "/cam/image_raw"] == stamps
    with AnyReader([out], default_typestore=get_typestore(Stores.EMPTY)) as any_reader:
        images = [raw for conn, _, raw in any_reader.messages()
                  if conn.topic == "/cam/image_raw"]
    with open_reader(source) as original:
        expected = [bytes(r.data) for r in original.raw_messages(["/cam/image_raw"])]
    assert [bytes(raw) for raw in images] == expected


class KeptBytes(io.BytesIO):
    """A file whose bytes can still be read after it is closed."""

    kept = b""

    def close(self) -> None:
        self.kept = self.getvalue()
        super().close()


def test_a_writer_given_its_file_closes_it_when_finished_or_aborted() -> None:
    theirs = io.BytesIO()
    writer = Writer(theirs, chunk_size=1024)
    writer.start(profile="ros2", library="test")
    writer.add_metadata("end", {"k": "v"})
    writer.finish()
    owned = KeptBytes()
    ours = McapChunkWriter(owned, chunk_size=1024, close_file=True)
    ours.start(profile="ros2", library="test")
    ours.finish({"end": {"k": "v"}})  # the metadata written first, as add_metadata does
    assert owned.closed and owned.kept == theirs.getvalue()
    aborted = io.BytesIO()
    McapChunkWriter(aborted, close_file=True).abort()
    assert aborted.closed
    kept = io.BytesIO()
    McapChunkWriter(kept).abort()
    assert not kept.closed
