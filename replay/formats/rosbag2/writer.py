"""rosbag2 directories written through ``rosbags``, with camlog's storage plugins
(:mod:`.storage_plugins`)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rosbags.rosbag2 import Writer as Writer2
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode, StoragePlugin

from ...errors import LogWriteError
from ...wire import CDR, ros2_typestore
from ..rosbags_reader import first_line
from ..rosbags_writer import RosbagsWriter
from .storage_plugins import McapStorage, Sqlite3Storage

__all__ = ["Rosbag2LogWriter"]

#: rosbag2 storage name -> (rosbags plugin, storage class, compressions it supports)
_STORAGES: dict[str, tuple[StoragePlugin, Any, tuple[str, ...]]] = {
    "mcap": (StoragePlugin.MCAP, McapStorage, ("zstd", "none")),
    "sqlite3": (StoragePlugin.SQLITE3, Sqlite3Storage, ("none", "zstd")),
}


class Rosbag2LogWriter(RosbagsWriter):
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
