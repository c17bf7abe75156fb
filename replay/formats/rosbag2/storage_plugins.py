"""rosbag2 storage writers that survive a killed process, plugged into ``rosbags``' writer.

``rosbags`` writes metadata.yaml, message definitions, type hashes and QoS; these classes
store the messages. The MCAP storage is written by :mod:`replay.formats.mcap.chunks`
(chunks with CRCs, zstd-compressed when asked, finished on a worker thread), the SQLite
storage commits what it holds at each flush and after every few megabytes instead of once at
the end.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rosbags.interfaces import MessageDefinitionFormat
from rosbags.rosbag2.enums import CompressionMode
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer

from ..._version import VERSION
from ..mcap.chunks import McapChunkWriter

#: an SQLite transaction is committed at least after this many bytes of messages
SQLITE_CHUNK_BYTES = 8 * 1024 * 1024


class McapStorage:
    """rosbag2 MCAP storage file written by the ``mcap`` library, as rosbag2's plugin does:
    ``ros2`` profile, ``ros2msg`` schemas, QoS in channel metadata, the serialized bag
    metadata in a ``rosbag2`` metadata record. ``CompressionMode.STORAGE`` means zstd chunks.
    """

    #: as rosbags' own MCAP storage
    CHUNK_SIZE = 1024 * 1024

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        self.path = path / f"{path.name}.mcap"
        self._file = self.path.open("xb")
        chunks = "zstd" if compression == CompressionMode.STORAGE else ""
        self._writer = McapChunkWriter(self._file, chunk_size=self.CHUNK_SIZE,
                                       compression=chunks, close_file=True)
        self._writer.start(profile="ros2", library=f"camlog {VERSION}")
        self._schemas: dict[str, int] = {}
        self._channels: dict[int, int] = {}  # rosbags connection id -> MCAP channel id
        self._sequence: dict[int, int] = {}

    def add_msgtype(self, connection: Any) -> None:
        """Register the schema of a message type."""
        encoding = "ros2msg" if connection.msgdef.format == MessageDefinitionFormat.MSG \
            else "ros2idl"
        self._schemas[connection.msgtype] = self._writer.register_schema(
            connection.msgtype, encoding, connection.msgdef.data.encode())

    def add_connection(self, connection: Any, offered_qos_profiles: str) -> None:
        """Register a topic's channel with its QoS."""
        self._channels[connection.id] = self._writer.register_channel(
            connection.topic, connection.ext.serialization_format,
            self._schemas[connection.msgtype], {"offered_qos_profiles": offered_qos_profiles})

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
        """Store one serialized message."""
        channel = self._channels[connection.id]
        sequence = self._sequence.get(channel, 0)
        self._sequence[channel] = sequence + 1
        self._writer.add_message(channel, timestamp, data, timestamp, sequence)  # copied

    def flush(self) -> None:
        """Complete the open chunk and hand it to the OS."""
        self._writer.flush()

    def close(self, version: int, metadata: str) -> None:
        """Write the summary (with the bag metadata, as rosbag2 does) and close the file."""
        del version
        self._writer.finish({"rosbag2": {"serialized_metadata": metadata}})

    def abort(self) -> None:
        """Close without a summary."""
        self._writer.abort()


class Sqlite3Storage(Sqlite3Writer):
    """``rosbags``' SQLite storage, committing at each flush and every few megabytes."""

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        super().__init__(path, compression)
        self._pending_bytes = 0

    def write(self, connection: Any, timestamp: int, data: bytes | memoryview) -> None:
        """Store one message; commit when a chunk's worth is pending."""
        super().write(connection, timestamp, data)
        self._pending_bytes += len(data)
        if self._pending_bytes >= SQLITE_CHUNK_BYTES:
            self.flush()

    def flush(self) -> None:
        """Commit the open transaction."""
        self.conn.commit()
        self._pending_bytes = 0
