"""Writing MCAP files with ROS 2 (CDR) messages (or Foxglove schemas).

Chunks are zstd-compressed by default, carry CRCs and are finished on a worker thread
(:mod:`.chunks`); a live writer completes a chunk at least every
:data:`~replay.formats.base.FLUSH_INTERVAL_S` so that a killed writer's file keeps all but
its last moments.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from ..._version import VERSION
from ...errors import LogWriteError
from ...wire import CDR, JSON, PROTOBUF, ros2_typestore
from ..base import LogWriter, RawMessage
from .chunks import McapChunkWriter

__all__ = ["COMPRESSION", "McapLogWriter"]

#: compression name -> its name in MCAP chunk records
COMPRESSION = {"zstd": "zstd", "lz4": "lz4", "none": ""}


class McapLogWriter(LogWriter):
    """Writer for one MCAP file with ``ros2msg`` schemas and CDR messages; its chunks
    compressed with ``compression`` at ``compression_level`` (None: the compressor's
    default)."""

    format_name = "mcap"
    serialization = CDR
    other_serializations = frozenset({PROTOBUF, JSON, "flatbuffer", "cbor", "msgpack"})

    def __init__(
        self,
        path: Path,
        *,
        overwrite: bool = False,
        inputs: Iterable[Path] = (),
        compression: str | None = None,
        compression_level: int | None = None,
        chunk_size: int = 4 * 1024 * 1024,
        profile: str = "ros2",
    ) -> None:
        compression = compression or "zstd"
        if compression not in COMPRESSION:
            raise LogWriteError(f"MCAP files cannot use {compression!r} compression "
                                "(use zstd, lz4 or none)")
        if profile not in ("ros2", "foxglove"):
            raise LogWriteError(f"unknown MCAP profile {profile!r} (use ros2 or foxglove)")
        super().__init__(path, overwrite=overwrite, inputs=inputs)
        self.compression = f"{compression} chunks" if compression != "none" else "none"
        self.profile = profile
        try:
            self._file = self.temp_path.open("wb")
        except OSError as err:
            raise LogWriteError(f"cannot write {path}: {err.strerror}") from None
        try:  # every chunk carries the CRC of its content
            self._writer = McapChunkWriter(self._file, chunk_size=chunk_size,
                                           compression=COMPRESSION[compression],
                                           level=compression_level, close_file=True)
            self._writer.start(profile="ros2" if profile == "ros2" else "",
                               library=f"camlog {VERSION}")
        except BaseException:  # e.g. Ctrl-C: no temporary file stays behind
            self._file.close()
            self._atomic.discard()
            raise
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}

    def _channel(self, raw: RawMessage, msgdef: str) -> int:
        channel = self._channels.get(raw.topic)
        if channel is not None:
            return channel
        foreign = raw.serialization != CDR  # protobuf, JSON...: the schema as it came
        key = f"{raw.serialization}:{raw.msgtype}" if foreign else raw.msgtype
        schema = self._schemas.get(key)
        if schema is None:
            if foreign:
                source = raw.schema
                schema = 0 if source is None else self._writer.register_schema(
                    source.name, source.encoding, source.data)
            else:
                if not msgdef:
                    try:
                        msgdef, _ = ros2_typestore().generate_msgdef(raw.msgtype, ros_version=2)
                    except Exception as err:  # rosbags raises several types for unknown names
                        raise LogWriteError(f"{raw.topic}: no message definition for "
                                            f"{raw.msgtype}") from err
                schema = self._writer.register_schema(raw.msgtype, "ros2msg", msgdef.encode())
            self._schemas[key] = schema
        channel = self._writer.register_channel(raw.topic, raw.serialization, schema)
        self._channels[raw.topic] = channel
        return channel

    def _write(self, raw: RawMessage, msgdef: str) -> None:
        channel = self._channel(raw, msgdef)
        sequence = self._sequence.get(channel, 0)
        self._sequence[channel] = sequence + 1
        self._writer.add_message(channel, raw.log_time_ns, raw.data, raw.log_time_ns, sequence)

    def set_metadata(self, name: str, values: dict[str, str]) -> None:
        self._writer.add_metadata(name, values)

    def _flush(self) -> None:
        self._writer.flush()  # chunk (with CRC) to the file

    def _finish(self) -> None:
        self._writer.finish()

    def _abort(self) -> None:
        self._writer.abort()
