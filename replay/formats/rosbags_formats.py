"""rosbag2 directories (mcap or sqlite3 storage) and ROS1 bags, through ``rosbags``."""

from __future__ import annotations

import contextlib
import sqlite3
import tempfile
import traceback
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import zstandard
from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag1.reader import Header, ReaderError, RecordType
from rosbags.rosbag2 import Reader as Reader2
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin

from ..errors import LogReadError, LogWriteError
from ..wire import CDR, ROS1, ros1_typestore, ros2_typestore
from .base import LogReader, LogWriter, RawMessage, TopicInfo
from .ros1_reindex import reindexed_copy
from .rosbag2_reindex import ZSTD_MAGIC, lone_storage, rolled_back_copy
from .rosbag2_storage import McapStorage, Sqlite3Storage


class _RosbagsReader(LogReader):
    """Shared reading over a rosbags reader object."""

    serialization = CDR

    def __init__(self, path: Path, reader: Any) -> None:
        super().__init__(path)
        self._reader = reader
        self._decompress = False  # zstd per message that rosbags does not know about
        try:
            reader.open()
        except Exception as err:  # rosbags raises ReaderError, OSError, sqlite errors...
            raise LogReadError(f"cannot read {path}: {_first_line(err)}") from None
        counts: dict[str, int] = {}
        self._by_topic: dict[str, list[Any]] = {}
        for conn in reader.connections:
            counts[conn.topic] = counts.get(conn.topic, 0) + conn.msgcount
            self._by_topic.setdefault(conn.topic, []).append(conn)
        for topic, conns in self._by_topic.items():
            msgdef = getattr(conns[0].msgdef, "data", "") or ""
            self.topics[topic] = TopicInfo(
                topic, conns[0].msgtype, counts[topic], self.serialization, msgdef
            )
        self.message_count = reader.message_count
        if self.message_count:
            self.start_ns = reader.start_time
            # rosbags' end_time lies one nanosecond after the last message
            self.end_ns = max(reader.end_time - 1, reader.start_time)

    def raw_messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
        end_ns: int | None = None,
    ) -> Iterator[RawMessage]:
        conns = (
            list(self._reader.connections)
            if topics is None
            else [c for t in topics for c in self._by_topic.get(t, [])]
        )
        if not conns:
            return
        try:
            for conn, timestamp, data in self._reader.messages(
                connections=conns, start=start_ns, stop=end_ns
            ):
                payload = zstandard.ZstdDecompressor().decompress(data) \
                    if self._decompress else data
                yield RawMessage(conn.topic, conn.msgtype, timestamp, payload, self.serialization)
        except Exception as err:
            raise LogReadError(f"cannot read {self.path}: {_first_line(err)}") from None

    def close(self) -> None:
        self._reader.close()


class Rosbag2LogReader(_RosbagsReader):
    """Reader for a rosbag2 directory (metadata.yaml + .mcap or .db3 files).

    A directory without metadata.yaml (the recording was cut short) is read from its one
    SQLite storage file up to its last commit, as ``ros2 bag reindex`` would (see
    :mod:`.rosbag2_reindex`; the input is never modified), with a warning.
    """

    format_name = "rosbag2"

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        self._scratch: tempfile.TemporaryDirectory[str] | None = None
        storage = None if (path / "metadata.yaml").exists() else lone_storage(path)
        try:
            opened = path if storage is None else self._recovered(storage)
            try:
                reader = Reader2(opened)
            except Exception as err:
                raise LogReadError(f"cannot read {path}: {_first_line(err)}") from None
            super().__init__(path, reader)
        except BaseException:
            self._close_scratch()
            raise
        kind = "sqlite3" if opened.suffix == ".db3" or any(
            f.suffix == ".db3" for f in path.iterdir()) else "mcap"
        self.format_name = f"rosbag2 ({kind})"
        if storage is not None:
            self._decompress = self._first_message_is_zstd()
            self.warnings.append(
                f"{path} has no metadata.yaml (its recording was cut short?); read its "
                f"storage file {storage.relative_to(path)} up to its last commit, as `ros2 "
                f"bag reindex` would: {self.message_count} messages")

    def _recovered(self, storage: Path) -> Path:
        self._scratch = tempfile.TemporaryDirectory(prefix="camlog-reindex-")
        try:
            return rolled_back_copy(storage, Path(self._scratch.name))
        except (OSError, sqlite3.Error) as err:
            raise LogReadError(f"cannot read {storage}: {_first_line(err)}") from None

    def _first_message_is_zstd(self) -> bool:
        """Whether messages carry rosbag2's per-message zstd compression, which only the
        missing metadata.yaml would have said."""
        for raw in self.raw_messages():
            return bytes(raw.data[:4]) == ZSTD_MAGIC
        return False

    def _close_scratch(self) -> None:
        if self._scratch is not None:
            self._scratch.cleanup()

    def close(self) -> None:
        try:
            super().close()
        finally:
            self._close_scratch()


class Ros1LogReader(_RosbagsReader):
    """Reader for a ROS1 ``.bag`` file (v2.0).

    A bag without its index (the recording was killed) is read through an indexed copy in a
    temporary folder, made from its complete chunks, with a warning.
    """

    format_name = "ros1"
    serialization = ROS1

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        self._scratch: tempfile.TemporaryDirectory[str] | None = None
        note = ""
        if _unindexed_ros1(path):
            self._scratch = tempfile.TemporaryDirectory(prefix="camlog-reindex-")
            copy = Path(self._scratch.name) / path.name
            try:
                done = reindexed_copy(path, copy)
            except Exception as err:
                self._scratch.cleanup()
                raise LogReadError(f"cannot reindex {path}: {_first_line(err)}") from None
            note = (f"{path} has no index (its recording was cut short); reading the "
                    f"{done.messages} messages of its complete chunks, up to byte "
                    f"{done.stopped_at} of {path.stat().st_size}")
            opened = copy
        else:
            opened = path
        try:
            reader = Reader1(opened)
            super().__init__(path, reader)
        except BaseException:
            if self._scratch is not None:
                self._scratch.cleanup()
            raise
        if note:
            self.warnings.append(note)

    def topic_spans(self) -> dict[str, tuple[int, int]] | None:
        """From the bag's index, which holds every message's time, sorted per connection."""
        spans: dict[str, tuple[int, int]] = {}
        for topic, conns in self._by_topic.items():
            ends = [entry.time for c in conns if (index := self._reader.indexes[c.id])
                    for entry in (index[0], index[-1])]
            if ends:
                spans[topic] = (min(ends), max(ends))
        return spans

    def close(self) -> None:
        try:
            super().close()
        finally:
            if self._scratch is not None:
                self._scratch.cleanup()


def _unindexed_ros1(path: Path) -> bool:
    """Whether a ROS1 bag's header says it has no index (``index_pos`` 0)."""
    try:
        with path.open("rb") as src:
            src.readline()
            return Header.read(src, RecordType.BAGHEADER).get_uint64("index_pos") == 0
    except (OSError, ReaderError):
        return False  # the reader reports what is wrong


class _RosbagsWriter(LogWriter):
    """Shared writing through a rosbags writer: one connection per topic.

    Errors of the storage below (OS errors, SQLite's "disk is full") become
    :class:`LogWriteError` naming the output.
    """

    _writer: Any

    def __init__(self, path: Path, *, overwrite: bool, inputs: Iterable[Path]) -> None:
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        self._conns: dict[str, Any] = {}

    def _open(self, writer: Any) -> None:
        self._writer = writer
        try:
            writer.open()
        except Exception as err:
            raise LogWriteError(f"cannot write {self.path}: {_first_line(err)}") from None

    def _typestore(self) -> Any:
        raise NotImplementedError

    def _write(self, raw: RawMessage, msgdef: str) -> None:
        try:
            conn = self._conns.get(raw.topic)
            if conn is None:
                conn = self._writer.add_connection(raw.topic, raw.msgtype,
                                                   typestore=self._typestore())
                self._conns[raw.topic] = conn
            self._writer.write(conn, raw.log_time_ns, bytes(raw.data))
        except (OSError, LogWriteError):
            raise
        except Exception as err:  # sqlite3.Error, rosbags' WriterError
            raise LogWriteError(f"cannot write {self.path}: {_first_line(err)}") from None

    def _finish(self) -> None:
        try:
            self._writer.close()
        except OSError:
            raise
        except Exception as err:
            raise LogWriteError(f"cannot write {self.path}: {_first_line(err)}") from None

    def _abort(self) -> None:
        with contextlib.suppress(Exception):  # the output is discarded anyway
            self._writer.abort()


#: rosbag2 storage name -> (rosbags plugin, storage class, compressions it supports)
_STORAGES: dict[str, tuple[StoragePlugin, Any, tuple[str, ...]]] = {
    "mcap": (StoragePlugin.MCAP, McapStorage, ("zstd", "none")),
    "sqlite3": (StoragePlugin.SQLITE3, Sqlite3Storage, ("none", "zstd")),
}


class Rosbag2LogWriter(_RosbagsWriter):
    """Writer for a rosbag2 directory; ``storage`` is ``mcap`` (default) or ``sqlite3``.

    ``compression``: ``zstd`` compresses MCAP chunks (storage compression, as ``ros2 bag
    record --storage-preset-profile`` does) or, with SQLite, each message (rosbag2's
    message compression); default zstd for MCAP, none for SQLite.
    """

    format_name = "rosbag2"
    serialization = CDR

    def __init__(self, path: Path, *, overwrite: bool = False, inputs: Iterable[Path] = (),
                 storage: str = "mcap", compression: str | None = None) -> None:
        if storage not in _STORAGES:
            raise LogWriteError(f"unknown rosbag2 storage {storage!r} (use mcap or sqlite3)")
        plugin, storage_class, compressions = _STORAGES[storage]
        compression = compressions[0] if compression is None else compression
        if compression not in compressions:
            raise LogWriteError(f"rosbag2 with {storage} storage cannot use {compression!r} "
                                f"compression (use {' or '.join(compressions)})")
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        self.format_name = f"rosbag2 ({storage})"
        writer = Writer2(self.temp_path / path.name, version=9, storage_plugin=plugin)
        writer.STORAGE_PLUGINS = {plugin: storage_class}
        if compression == "zstd":
            mode = CompressionMode.STORAGE if storage == "mcap" else CompressionMode.MESSAGE
            writer.set_compression(mode, CompressionFormat.ZSTD)
            self.compression = "zstd chunks" if storage == "mcap" else "zstd per message"
        # rosbags names the storage file after its directory: write it one folder down in
        # the temporary output, so that the final directory holds files named after itself
        self.temp_path.mkdir()
        self._open(writer)

    def _typestore(self) -> Any:
        return ros2_typestore()

    def set_metadata(self, name: str, values: dict[str, str]) -> None:
        for key, value in values.items():
            self._writer.set_custom_data(f"{name}.{key}", value)

    def _flush(self) -> None:
        try:
            self._writer.storage.flush()
        except OSError:
            raise
        except Exception as err:  # sqlite3.Error
            raise LogWriteError(f"cannot write {self.path}: {_first_line(err)}") from None

    def _commit(self) -> None:
        self._atomic.commit(self.temp_path / self.path.name)


class Ros1LogWriter(_RosbagsWriter):
    """Writer for a ROS1 ``.bag`` file (lz4-compressed chunks by default)."""

    format_name = "ros1"
    serialization = ROS1

    def __init__(self, path: Path, *, overwrite: bool = False, inputs: Iterable[Path] = (),
                 compression: str | None = None) -> None:
        formats = {"lz4": Writer1.CompressionFormat.LZ4, "bz2": Writer1.CompressionFormat.BZ2,
                   "none": None}
        compression = "lz4" if compression is None else compression
        if compression not in formats:
            raise LogWriteError(f"ROS1 bags cannot use {compression!r} compression "
                                f"(use {', '.join(formats)})")
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        writer = Writer1(self.temp_path)
        if (chunk_format := formats[compression]) is not None:
            writer.set_compression(chunk_format)
        self.compression = f"{compression} chunks" if compression != "none" else "none"
        self._open(writer)

    def _typestore(self) -> Any:
        return ros1_typestore()

    def _flush(self) -> None:
        writer = self._writer
        writer.write_chunk(writer.chunks[-1])  # the open chunk; rosbags starts a new one
        writer.bio.flush()


def _first_line(err: BaseException) -> str:
    """The first line of an error's message; for a bare one (rosbags' ``assert`` checks of
    a damaged index or record), what kind of check failed and where."""
    text = str(err).strip()
    if text:
        return text.splitlines()[0]
    frames = traceback.extract_tb(err.__traceback__)
    where = f" in {Path(frames[-1].filename).name}:{frames[-1].lineno}" if frames else ""
    return f"malformed data ({type(err).__name__}{where})"
