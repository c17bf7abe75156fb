"""Log formats behind one interface, chosen by name or detected from the path."""

from __future__ import annotations

import shutil
import tempfile
import weakref
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .. import storage
from ..atomic import temp_output_of
from ..errors import LogFormatError, LogReadError
from ..format_names import WRITE_FORMATS
from .base import FrameRecord, LogReader, LogWriter, RawMessage, Record, TopicInfo
from .mcap import MAGIC, McapLogReader, is_mcap
from .rosbag2.metadata import BagMetadata, count_warnings, read_metadata
from .rosbag2.reindex import lone_storage

__all__ = [
    "FORMATS",
    "FrameRecord",
    "LogReader",
    "LogWriter",
    "RawMessage",
    "Record",
    "TopicInfo",
    "detect_format",
    "format_for_output",
    "open_reader",
    "open_writer",
]

ROS1_MAGIC = b"#ROSBAG V2.0"

# Each format's library (rosbags, the MCAP writer) is imported when the format is first used,
# so that reading an MCAP file or parsing arguments does not load the others.


def _mcap_writer(path: Path, **options: Any) -> LogWriter:
    from .mcap.writer import McapLogWriter

    return McapLogWriter(path, **options)


def _rosbag2_writer(storage_name: str) -> Callable[..., LogWriter]:
    def create(path: Path, **options: Any) -> LogWriter:
        from .rosbag2.writer import Rosbag2LogWriter

        return Rosbag2LogWriter(path, storage=storage_name, **options)
    return create


def _ros1_writer(path: Path, **options: Any) -> LogWriter:
    from .ros1.writer import Ros1LogWriter

    return Ros1LogWriter(path, **options)


def _rosbag2_reader(path: Path, **options: Any) -> LogReader:
    from .rosbag2.reader import Rosbag2LogReader

    return Rosbag2LogReader(path, **options)


def _ros1_reader(path: Path, **options: Any) -> LogReader:
    from .ros1.reader import Ros1LogReader

    return Ros1LogReader(path, **options)


#: format name -> writer factory
FORMATS: dict[str, Callable[..., LogWriter]] = {
    "mcap": _mcap_writer,
    "rosbag2": _rosbag2_writer("mcap"),
    "rosbag2-sqlite3": _rosbag2_writer("sqlite3"),
    "ros1": _ros1_writer,
}
assert tuple(FORMATS) == WRITE_FORMATS

READERS: dict[str, Callable[..., LogReader]] = {
    "mcap": McapLogReader,
    "rosbag2": _rosbag2_reader,
    "ros1": _ros1_reader,
}


def detect_format(path: Path) -> str:
    """Reader format name for an existing log path."""
    if not path.exists():
        raise LogReadError(f"{path} does not exist")
    if path.is_dir():
        if (path / "metadata.yaml").exists():
            return "rosbag2"
        storage = lone_storage(path)
        if storage is not None:
            return "mcap" if storage.suffix == ".mcap" else "rosbag2"
        raise LogFormatError(f"{path} is a directory without rosbag2 metadata.yaml or one "
                             "storage file (.mcap, .db3)")
    try:
        with path.open("rb") as f:
            head = f.read(16)
    except OSError as err:
        raise LogReadError(f"cannot open {path}: {err.strerror}") from None
    if is_mcap(path):
        return "mcap"
    if head.startswith(ROS1_MAGIC):
        return "ros1"
    if path.suffix == ".db3" and (path.parent / "metadata.yaml").exists():
        return "rosbag2"
    if not head:
        raise LogReadError(f"{path} is empty")
    raise LogFormatError(f"{path} is not a log camlog can read (MCAP, rosbag2 directory, ROS1 bag)")


def open_reader(path: str | Path, *, recover: bool = False) -> LogReader:
    """Open any supported log for streaming reads: a path, a ``file://`` URI or an object
    (``s3://bucket/run.mcap``; see :mod:`replay.storage`)."""
    if storage.is_remote(path):
        return _open_remote(str(path), recover=recover)
    path = storage.local_path(path)
    reader = _open(path, recover=recover)
    final = temp_output_of(path)
    if final is not None:
        reader.warnings.insert(0, f"{path} is camlog's temporary output for {final.name}, "
                                  "left by a run that did not finish")
    return reader


def _open(path: Path, *, recover: bool) -> LogReader:
    fmt = detect_format(path)
    if path.is_dir() and fmt == "mcap":
        inner = lone_storage(path)
        assert inner is not None
        reader = McapLogReader(inner, recover=recover)
        reader.warnings.insert(0, f"{path} has no metadata.yaml (its recording was cut "
                                  f"short?); reading its storage file "
                                  f"{inner.relative_to(path)} directly")
        return reader
    if fmt == "rosbag2" and path.is_file():
        path = path.parent
    if fmt == "rosbag2" and (path / "metadata.yaml").exists():
        metadata = read_metadata(path)
        storage = _mcap_storage(path, metadata)
        if storage is not None:
            return _rosbag2_mcap(path, storage, metadata, recover=recover)
    return READERS[fmt](path, recover=recover)


def _mcap_storage(folder: Path, metadata: BagMetadata | str) -> Path | None:
    """The one MCAP storage file of a rosbag2 folder that camlog's MCAP reader can read
    (None: split over several files, per-message compression or SQLite storage)."""
    if isinstance(metadata, str):
        storage = lone_storage(folder)
        return storage if storage is not None and storage.suffix == ".mcap" else None
    files = set(metadata.files)  # a file listed twice is one file
    if metadata.storage != "mcap" or metadata.message_compression or len(files) != 1:
        return None
    storage = folder / files.pop()
    return storage if storage.is_file() else None


def _rosbag2_mcap(folder: Path, storage: Path, metadata: BagMetadata | str, *,
                  recover: bool) -> LogReader:
    """A rosbag2 folder with MCAP storage, read by the MCAP reader (CRCs checked, lengths
    bounded, ``recover`` past damaged chunks); counts come from the storage, with a warning
    where metadata.yaml disagrees or does not parse."""
    try:
        file = storage.open("rb")
    except OSError as err:
        raise LogReadError(f"cannot open {storage}: {err.strerror}") from None
    reader = McapLogReader(folder, file=file, recover=recover)
    reader.format_name = "rosbag2 (mcap)"
    reader.metadata.pop("rosbag2", None)  # the storage's copy of metadata.yaml
    if isinstance(metadata, str):
        reader.warnings.append(f"{folder}: {metadata}; read its storage file {storage.name} "
                               "directly")
    else:
        reader.warnings += count_warnings(
            folder, metadata, {name: info.count for name, info in reader.topics.items()})
    return reader


def _open_remote(uri: str, *, recover: bool) -> LogReader:
    """MCAP is read in place with range requests; other formats from a temporary copy."""
    if not storage.is_dir(uri):
        file = storage.open_remote(uri)
        try:
            head = file.read(len(MAGIC))
            file.seek(0)
        except Exception:
            file.close()
            raise
        if head == MAGIC:
            return McapLogReader(uri, file=file, recover=recover)
        file.close()
    folder = Path(tempfile.mkdtemp(prefix="camlog-download-"))
    try:
        reader = open_reader(storage.download(uri, folder), recover=recover)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    weakref.finalize(reader, shutil.rmtree, folder, True)
    reader.warnings.append(f"{uri} is read from a temporary download (only MCAP is read in "
                           "place with range requests)")
    return reader


def format_for_output(path: Path, fmt: str | None = None) -> str:
    """Writer format from an explicit name or the output path's suffix."""
    if fmt is not None:
        if fmt not in FORMATS:
            raise LogFormatError(f"unknown log format {fmt!r} (choose from {', '.join(FORMATS)})")
        return fmt
    match path.suffix:
        case ".mcap":
            return "mcap"
        case ".bag":
            return "ros1"
        case "":
            return "rosbag2"
    raise LogFormatError(
        f"cannot tell the log format from {path.name!r}: use .mcap, .bag, a directory name "
        f"(rosbag2) or --format"
    )


def open_writer(
    path: str | Path, *, fmt: str | None = None, overwrite: bool = False, live: bool = False,
    **options: Any
) -> LogWriter:
    """Create a log writer; the output appears atomically when it is closed. ``live``: the
    messages arrive as they happen (a recording): flush at least every
    :data:`~.base.FLUSH_INTERVAL_S` so a killed process keeps all but its last moments;
    otherwise chunks are completed by size only, and the same messages give the same bytes."""
    path = Path(path)
    writer = FORMATS[format_for_output(path, fmt)](path, overwrite=overwrite, **options)
    writer.live = live
    return writer
