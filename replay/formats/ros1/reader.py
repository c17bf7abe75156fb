"""ROS1 bags read through ``rosbags``; a bag without index or with damage through a reindexed
copy."""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import BinaryIO, cast

from rosbags.rosbag1 import Reader as Reader1
from rosbags.rosbag1.reader import Header, ReaderError, RecordType

from ...errors import LogReadError
from ...wire import ROS1
from ..bounded_file import BoundedFile
from ..rosbags_reader import RosbagsReader, first_line
from .layout import layout_problem
from .reindex import Reindexed, reindexed_copy

__all__ = ["Ros1LogReader"]


class Ros1LogReader(RosbagsReader):
    """Reader for a ROS1 ``.bag`` file (v2.0).

    A bag without its index (the recording was killed) is read through an indexed copy in a
    temporary folder, made from its complete chunks, with a warning. Every record's lengths
    and the index's offsets are checked first (:mod:`.layout`): a bag where they do not
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
