"""What a rosbag2 folder's metadata.yaml says, read without trusting it.

``rosbags`` takes topics, counts and times from metadata.yaml as written; a damaged file (a
line repeated, a value of the wrong type) gives a topic 0 messages or fails deep inside it.
:func:`read_metadata` reads only what camlog needs to choose a reader and to check the
storage against (storage name, files, message count per topic), with every type checked;
what is wrong comes back as one line instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ...bounded import MAX_RECORD_BYTES, read_text, yaml_load

__all__ = ["BagMetadata", "count_warnings", "read_metadata"]


@dataclass(frozen=True)
class BagMetadata:
    """The parts of metadata.yaml camlog relies on."""

    storage: str  # "mcap", "sqlite3", ...
    files: tuple[str, ...]  # storage files, relative to the folder
    counts: dict[str, int]  # topic -> message count
    message_compression: bool  # rosbag2's per-message compression


def read_metadata(folder: Path) -> BagMetadata | str:
    """The metadata of a rosbag2 folder, or what is wrong with its metadata.yaml."""
    from ruamel.yaml.error import YAMLError

    try:
        text = read_text(folder / "metadata.yaml", ValueError, max_bytes=MAX_RECORD_BYTES)
        document = yaml_load(text, "it", ValueError, max_bytes=MAX_RECORD_BYTES, pure=False)
    except (ValueError, YAMLError) as err:
        return f"metadata.yaml does not parse ({_first_line(err)})"
    try:
        return _metadata(document)
    except (TypeError, KeyError) as err:
        return f"metadata.yaml is malformed ({_first_line(err)})"


def _metadata(document: Any) -> BagMetadata:
    info = _field(document, "rosbag2_bagfile_information", dict)
    counts: dict[str, int] = {}
    for entry in _field(info, "topics_with_message_count", list):
        name = _field(_field(entry, "topic_metadata", dict), "name", str)
        count = _field(entry, "message_count", int)
        if count < 0:
            raise TypeError(f"topic {name}: message count {count}")
        counts[name] = counts.get(name, 0) + count
    files = tuple(_field(info, "relative_file_paths", list))
    if not all(isinstance(f, str) and f and Path(f).name == f for f in files):
        raise TypeError("relative_file_paths holds something other than file names")
    mode = info.get("compression_mode") or ""
    return BagMetadata(_field(info, "storage_identifier", str), files, counts,
                       str(mode).lower() == "message")


def _field(mapping: Any, key: str, kind: type) -> Any:
    if not isinstance(mapping, dict) or key not in mapping:
        raise KeyError(key)
    value = mapping[key]
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        raise TypeError(f"{key} is {value!r}, not {kind.__name__}")
    return value


def count_warnings(folder: Path, metadata: BagMetadata, counts: dict[str, int]) -> list[str]:
    """One line per topic whose count in metadata.yaml differs from what its storage holds
    (``counts``), which is what is reported."""
    return [f"{folder}: metadata.yaml counts {metadata.counts.get(topic, 0)} messages on "
            f"{topic}, its storage holds {count}; counting from the storage"
            for topic, count in sorted(counts.items())
            if metadata.counts.get(topic) != count]


def _first_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__
