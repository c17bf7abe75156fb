"""ROS1 bags (read and written) and rosbag2 directories (written), through ``rosbags``."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any, BinaryIO, cast

from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag1.reader import Header, ReaderError, RecordType
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin

from ..errors import LogReadError, LogWriteError
from ..wire import CDR, ROS1, ros1_typestore, ros2_typestore
from .base import LogWriter, RawMessage
from .bounded import BoundedFile
from .ros1_chunks import ThreadedRos1Writer
from .ros1_layout import layout_problem
from .ros1_reindex import Reindexed, reindexed_copy
from .rosbag2_storage import McapStorage, Sqlite3Storage
from .rosbags_reader import RosbagsReader, first_line


class Ros1LogReader(RosbagsReader):
    """Reader for a ROS1 ``.bag`` file (v2.0).

    A bag without its index (the recording was killed) is read through an indexed copy in a
    temporary folder, made from its complete chunks, with a warning. Every record's lengths
    and the index's offsets are checked first (:mod:`.ros1_layout`): a bag where they do not
    hold is refused, or with ``recover`` read like an unindexed one.
    """

    format_name = "ros1"
    serialization = ROS1

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        self._scratch: tempfile.TemporaryDirectory[str] | None = None
        notes: list[str] = []
        try:
            unindexed = _unindexed_ros1(path)
            problem = None if unindexed else layout_problem(path)
        except OSError as err:
            raise LogReadError(f"cannot read {path}: {err.strerror or err}") from None
        if problem is not None and not recover:
            raise LogReadError(f"{path} is corrupt: {problem}; use --recover to read the "
                               "chunks around the damage")
        if not recover:
            self.recover_hint = "; use --recover to read the chunks around the damage"
        opened = path
        if recover or unindexed:  # rebuilt from its chunks, past damage with recover
            self._scratch = tempfile.TemporaryDirectory(prefix="camlog-reindex-")
            opened = Path(self._scratch.name) / path.name
            try:
                done = reindexed_copy(path, opened, resync=recover)
            except Exception as err:
                self._scratch.cleanup()
                raise LogReadError(f"cannot reindex {path}: {first_line(err)}") from None
            notes = _reindex_notes(path, done, unindexed=unindexed, problem=problem)
        try:
            reader = Reader1(opened)
            super().__init__(path, reader)
        except BaseException:
            if self._scratch is not None:
                self._scratch.cleanup()
            raise
        self.warnings += notes

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


def _reindex_notes(path: Path, done: Reindexed, *, unindexed: bool,
                   problem: str | None) -> list[str]:
    """Warnings about a bag read through a reindexed copy: why, and what was lost."""
    notes = []
    if unindexed or problem is not None or done.reason != "end of file":
        why = "has no index (its recording was cut short)" if unindexed \
            else f"is damaged ({problem or done.reason})"
        notes.append(f"{path} {why}; reading the {done.messages} messages of its complete "
                     f"chunks, up to byte {done.stopped_at} of {path.stat().st_size}")
    for gap in done.skipped:
        times = f"{'start' if gap.first_ns is None else gap.first_ns} to " \
                f"{'end' if gap.last_ns is None else gap.last_ns} ns"
        lost = f"{gap.messages} messages lost, log times {times}" if gap.messages is not None \
            else f"messages lost between log times {times} (the bag's index does not say " \
                 "how many)"
        notes.append(f"{path}: skipped bytes {gap.start} to {gap.end} ({gap.reason}): {lost}")
    return notes


def _unindexed_ros1(path: Path) -> bool:
    """Whether a ROS1 bag's header says it has no index (``index_pos`` 0)."""
    try:
        with BoundedFile(path.open("rb")) as src:  # a damaged length reads what is there
            src.readline()
            return Header.read(cast(BinaryIO, src), RecordType.BAGHEADER) \
                .get_uint64("index_pos") == 0
    except (OSError, ReaderError, ValueError):  # ValueError: e.g. a field name not UTF-8
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
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _typestore(self) -> Any:
        raise NotImplementedError

    def _write(self, raw: RawMessage, msgdef: str) -> None:
        try:
            conn = self._conns.get(raw.topic)
            if conn is None:
                conn = self._writer.add_connection(raw.topic, raw.msgtype,
                                                   typestore=self._typestore())
                self._conns[raw.topic] = conn
            self._writer.write(conn, raw.log_time_ns, raw.data)  # copied into its chunk
        except (OSError, LogWriteError):
            raise
        except Exception as err:  # sqlite3.Error, rosbags' WriterError
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _finish(self) -> None:
        try:
            self._writer.close()
        except OSError:
            raise
        except Exception as err:
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

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
            raise LogWriteError(f"cannot write {self.path}: {first_line(err)}") from None

    def _commit(self) -> None:
        self._atomic.commit(self.temp_path / self.path.name)


class Ros1LogWriter(_RosbagsWriter):
    """Writer for a ROS1 ``.bag`` file (lz4-compressed chunks by default, finished on a worker
    thread: :mod:`.ros1_chunks`)."""

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
        writer = ThreadedRos1Writer(self.temp_path)
        if (chunk_format := formats[compression]) is not None:
            writer.set_compression(chunk_format)
        self.compression = f"{compression} chunks" if compression != "none" else "none"
        self._open(writer)

    def _typestore(self) -> Any:
        return ros1_typestore()

    def _flush(self) -> None:
        self._writer.flush()
