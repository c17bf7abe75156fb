"""Log locations: file objects, file:// URIs and fsspec filesystems (in-memory, no server)."""

from __future__ import annotations

import io
from pathlib import Path

import fsspec
import pytest
from mcap.reader import make_reader

from replay import open_reader, storage
from replay.errors import StorageError
from replay.formats.mcap import McapLogReader

from .samples import T0_NS, read_log, write_log
from .test_mcap import numbered_images


class CountingFile(io.BufferedReader):
    """A local file that counts the bytes read through it."""

    bytes_read = 0

    def read(self, size: int | None = -1, /) -> bytes:
        data = super().read(size)
        self.bytes_read += len(data)
        return data


@pytest.fixture
def chunked_log(tmp_path: Path) -> Path:
    """200 images in chunks of about 64 KiB (a few hundred KiB)."""
    path = tmp_path / "chunked.mcap"
    write_log(path, numbered_images(200), chunk_size=64 * 1024)
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and len(summary.chunk_indexes) > 10
    return path


def test_a_file_object_is_read_by_range_not_whole(chunked_log: Path) -> None:
    file = CountingFile(io.FileIO(chunked_log, "rb"))
    start_ns = T0_NS + 190 * 33_000_000  # the last ten frames
    with McapLogReader("any://name.mcap", file=file) as reader:
        assert reader.path == "any://name.mcap"
        assert reader.message_count == 200
        frames = [r.log_time_ns for r in reader.messages(start_ns=start_ns)]
    assert frames == [T0_NS + i * 33_000_000 for i in range(190, 200)]
    assert file.closed  # the reader owns it
    # summary plus the last chunk or two, not the whole file
    assert file.bytes_read < chunked_log.stat().st_size / 5


def test_file_uri_and_memory_filesystem_read_the_same(chunked_log: Path, tmp_path: Path) -> None:
    expected = read_log(chunked_log)
    assert read_log(Path(f"{chunked_log}")) == expected
    with open_reader(f"file://{chunked_log}") as reader:
        assert reader.message_count == 200
    memory = fsspec.filesystem("memory")
    memory.pipe("/bucket/logs/chunked.mcap", chunked_log.read_bytes())
    uri = "memory://bucket/logs/chunked.mcap"
    with open_reader(uri) as reader:
        assert isinstance(reader, McapLogReader) and reader.path == uri
        assert reader.warnings == []  # read in place
        assert [(r.topic, r.log_time_ns, r.message) for r in reader.messages()] == expected
    assert storage.identity(uri)["bytes"] == chunked_log.stat().st_size
    assert storage.expand("memory://bucket/logs/*.mcap") == [uri]


def test_other_formats_are_downloaded_with_a_note(chunked_log: Path, tmp_path: Path) -> None:
    bag = tmp_path / "log.bag"
    write_log(bag, numbered_images(5))
    memory = fsspec.filesystem("memory")
    memory.pipe("/bucket/bags/log.bag", bag.read_bytes())
    with open_reader("memory://bucket/bags/log.bag") as reader:
        assert reader.format_name == "ros1"
        assert reader.message_count == 5
        assert any("temporary download" in w for w in reader.warnings)
    folder = tmp_path / "run1"  # a rosbag2 folder: a prefix with several objects below it
    write_log(folder, numbered_images(4), fmt="rosbag2")
    memory.put(str(folder), "/bucket/bags/run1", recursive=True)
    uri = "memory://bucket/bags/run1"
    with open_reader(uri) as reader:
        assert reader.format_name.startswith("rosbag2")
        assert [r.log_time_ns for r in reader.messages()] == \
            [t for _, t, _ in numbered_images(4)]
        assert any("temporary download" in w for w in reader.warnings)
    local = storage.identity(folder)
    assert storage.identity(uri)["bytes"] == local["bytes"]


def test_locations_and_their_errors(tmp_path: Path) -> None:
    assert not storage.is_remote(tmp_path) and not storage.is_remote(f"file://{tmp_path}")
    assert storage.is_remote("s3://bucket/x.mcap")
    assert storage.local_path(f"file://{tmp_path}/a.mcap") == tmp_path / "a.mcap"
    assert storage.join("s3://bucket/out/", "cam1", "x") == "s3://bucket/out/cam1/x"
    assert storage.join(tmp_path, "cam1") == tmp_path / "cam1"
    storage.write_bytes(storage.join("memory://bucket/out", "s.json"), b"{}")
    assert storage.read_bytes("memory://bucket/out/s.json") == b"{}"
    storage.remove("memory://bucket/out/s.json")
    assert not storage.exists("memory://bucket/out/s.json")
    with pytest.raises(StorageError, match=r"memory://bucket/none\.mcap does not exist"):
        open_reader("memory://bucket/none.mcap")
    with pytest.raises(StorageError, match=r"gs://bucket/x\.mcap") as err:
        open_reader("gs://bucket/x.mcap")  # gcsfs is not installed
    assert "\n" not in str(err.value)


def test_local_and_remote_locations_answer_alike(tmp_path: Path) -> None:
    fsspec.filesystem("memory").pipe("/bucket/keep/dir/x", b"1")
    for base in (tmp_path, "memory://bucket/alike"):
        location = storage.join(base, "sub", "s.json")
        assert not storage.exists(location)
        storage.write_bytes(location, b"{}")
        assert storage.exists(location) and storage.read_bytes(location) == b"{}"
        assert storage.size(location) == 2
        storage.remove(location)
        storage.remove(location)  # a missing file: nothing to do
        assert not storage.exists(location)
    download = tmp_path / "download"
    download.mkdir()
    for failing, text in [
        (lambda: storage.read_bytes("memory://bucket/none"), "memory://bucket/none does not exist"),
        (lambda: storage.identity("memory://bucket/none"), "memory://bucket/none does not exist"),
        (lambda: storage.download("memory://bucket/none", download),
         "memory://bucket/none does not exist"),
        (lambda: storage.remove("memory://bucket/keep/dir"),
         "cannot delete memory://bucket/keep/dir: FileNotFoundError: /bucket/keep/dir"),
        (lambda: storage.write_bytes("memory://bucket/keep/dir/x/y", b""),
         "cannot write memory://bucket/keep/dir/x/y: FileExistsError: /bucket/keep/dir/x"),
        (lambda: storage.expand("memory://bucket/keep/*.q"), "memory://bucket/keep/*.q matches "
                                                             "nothing"),
    ]:
        with pytest.raises(StorageError) as raised:
            failing()
        assert str(raised.value) == text
