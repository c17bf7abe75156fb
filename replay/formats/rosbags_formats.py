"""rosbag2 directories (mcap or sqlite3 storage) and ROS1 bags, through ``rosbags``."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag1.reader import Header, ReaderError, RecordType
from rosbags.rosbag2 import Reader as Reader2
from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import StoragePlugin

from ..errors import LogReadError, LogWriteError
from ..wire import CDR, ROS1, ros1_typestore, ros2_typestore
from .base import LogReader, LogWriter, RawMessage, TopicInfo
from .ros1_reindex import reindexed_copy


class _RosbagsReader(LogReader):
    """Shared reading over a rosbags reader object."""

    serialization = CDR

    def __init__(self, path: Path, reader: Any) -> None:
        super().__init__(path)
        self._reader = reader
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
                yield RawMessage(conn.topic, conn.msgtype, timestamp, data, self.serialization)
        except Exception as err:
            raise LogReadError(f"cannot read {self.path}: {_first_line(err)}") from None

    def close(self) -> None:
        self._reader.close()


class Rosbag2LogReader(_RosbagsReader):
    """Reader for a rosbag2 directory (metadata.yaml + .mcap or .db3 files)."""

    format_name = "rosbag2"

    def __init__(self, path: Path, *, recover: bool = False) -> None:
        try:
            reader = Reader2(path)
        except Exception as err:
            raise LogReadError(f"cannot read {path}: {_first_line(err)}") from None
        super().__init__(path, reader)
        storage = "sqlite3" if any(f.suffix == ".db3" for f in path.iterdir()) else "mcap"
        self.format_name = f"rosbag2 ({storage})"


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
    """Shared writing through a rosbags writer: one connection per topic."""

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
        conn = self._conns.get(raw.topic)
        if conn is None:
            conn = self._writer.add_connection(raw.topic, raw.msgtype,
                                               typestore=self._typestore())
            self._conns[raw.topic] = conn
        self._writer.write(conn, raw.log_time_ns, bytes(raw.data))

    def _finish(self) -> None:
        self._writer.close()

    def _abort(self) -> None:
        with contextlib.suppress(Exception):  # the output is discarded anyway
            self._writer.close()


class Rosbag2LogWriter(_RosbagsWriter):
    """Writer for a rosbag2 directory; ``storage`` is ``mcap`` (default) or ``sqlite3``."""

    format_name = "rosbag2"
    serialization = CDR

    def __init__(self, path: Path, *, overwrite: bool = False, inputs: Iterable[Path] = (),
                 storage: str = "mcap") -> None:
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}.get(storage)
        if plugin is None:
            raise LogWriteError(f"unknown rosbag2 storage {storage!r} (use mcap or sqlite3)")
        # rosbags names the storage file after its directory: write it one folder down in
        # the temporary output, so that the final directory holds files named after itself
        self.temp_path.mkdir()
        self._open(Writer2(self.temp_path / path.name, version=9, storage_plugin=plugin))

    def _typestore(self) -> Any:
        return ros2_typestore()

    def set_metadata(self, name: str, values: dict[str, str]) -> None:
        for key, value in values.items():
            self._writer.set_custom_data(f"{name}.{key}", value)

    def _commit(self) -> None:
        self._atomic.commit(self.temp_path / self.path.name)


class Ros1LogWriter(_RosbagsWriter):
    """Writer for a ROS1 ``.bag`` file (lz4-compressed chunks)."""

    format_name = "ros1"
    serialization = ROS1

    def __init__(self, path: Path, *, overwrite: bool = False,
                 inputs: Iterable[Path] = ()) -> None:
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        writer = Writer1(self.temp_path)
        writer.set_compression(Writer1.CompressionFormat.LZ4)
        self._open(writer)

    def _typestore(self) -> Any:
        return ros1_typestore()


def _first_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__
