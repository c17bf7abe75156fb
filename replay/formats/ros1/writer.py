"""ROS1 bags written through ``rosbags``, chunks finished on a worker thread."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rosbags.rosbag1 import Writer as Writer1

from ...errors import LogWriteError
from ...wire import ROS1, ros1_typestore
from ..rosbags_writer import RosbagsWriter
from .chunks import ThreadedRos1Writer

__all__ = ["Ros1LogWriter"]


class Ros1LogWriter(RosbagsWriter):
    """Writer for a ROS1 ``.bag`` file (lz4-compressed chunks by default, finished on a worker
    thread: :mod:`.chunks`)."""

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
