"""Rows that rerun receives as columns: many frames of one entity in one ``send_columns``.

Logging an image through ``rr.Image`` costs about 0.3 ms of Python per frame (the archetype's
converters, then ``log``), more than rerun takes to store it. A :class:`Row` is the plain
data of one frame (an image's pixels, a frame's points, a clear); :class:`ColumnBatcher`
gathers an entity's consecutive rows of the same shape and sends them at once, with their
times as index columns. Rows of one entity keep their order (a batch is sent before a row
of another kind, or any other log call, reaches that entity), so rerun stores what it would
have stored from one ``log`` call per row.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pyarrow as pa
import rerun as rr

from .blueprint import LOG_TIME, REPLAY_TIME, STAMP_TIME

__all__ = ["BUFFER_TYPE", "MAX_BATCH_BYTES", "MAX_ROWS", "ClearRow", "ColumnBatcher", "ImageRow",
           "PointsRow", "Row"]

#: rows of one entity sent together at most
MAX_ROWS = 32
#: bytes of pixels held back over all entities at most (bounds memory)
MAX_BATCH_BYTES = 8 << 20

#: rerun's arrow type of an image buffer (``rr.components.ImageBuffer``)
BUFFER_TYPE = pa.list_(pa.field("item", pa.uint8(), nullable=False))

#: (log time, header stamp or None, replay wall clock or None), ns
Times = tuple[int, int | None, int | None]
ColorModel = Literal["RGB", "BGR", "RGBA", "BGRA", "L"]


@dataclass(frozen=True, slots=True)
class ImageRow:
    """An image's pixels ``(H, W)`` or ``(H, W, C)`` in ``color_model`` order."""

    pixels: np.ndarray
    color_model: ColorModel
    draw_order: float | None = None

    def key(self) -> tuple[Any, ...]:
        """Rows with equal keys share their format and go in one batch."""
        return (ImageRow, self.pixels.shape, self.pixels.dtype.str, self.color_model,
                self.draw_order)

    @property
    def nbytes(self) -> int:
        """Bytes of pixels the row holds."""
        return int(self.pixels.nbytes)

    def archetype(self) -> Any:
        """The row as one ``log`` call's archetype."""
        return rr.Image(self.pixels, color_model=self.color_model, draw_order=self.draw_order)

    @staticmethod
    def columns(rows: Sequence[ImageRow]) -> Any:
        """The component columns of ``rows`` (equal keys)."""
        first = rows[0]
        height, width = first.pixels.shape[:2]
        image_format = rr.components.ImageFormat(
            width=width, height=height, color_model=first.color_model,
            channel_datatype=rr.ChannelDatatype.from_np_dtype(first.pixels.dtype))
        draw_order = None if first.draw_order is None else [first.draw_order] * len(rows)
        return rr.Image.columns(buffer=_buffers(rows), format=[image_format] * len(rows),
                                draw_order=draw_order)


def _buffers(rows: Sequence[ImageRow]) -> pa.Array:
    """The rows' pixels as rerun's image buffer column: their bytes copied once into one
    array, each row a list over its part (rerun's own conversion copies each image three
    times, several times slower than the image's other work)."""
    sizes = [row.pixels.nbytes for row in rows]
    values = np.empty(sum(sizes), dtype=np.uint8)
    offsets = np.zeros(len(rows) + 1, dtype=np.int32)
    np.cumsum(sizes, out=offsets[1:])
    for row, start, end in zip(rows, offsets[:-1], offsets[1:], strict=True):
        values[start:end] = np.ascontiguousarray(row.pixels).reshape(-1).view(np.uint8)
    return pa.ListArray.from_arrays(pa.array(offsets), pa.array(values), type=BUFFER_TYPE)


@dataclass(frozen=True, slots=True)
class PointsRow:
    """The positions ``(N, 2)`` of a frame's 2D points, or ``(N, 3)`` of its 3D points
    (their style is logged statically)."""

    positions: np.ndarray

    def key(self) -> tuple[Any, ...]:
        """Points rows of one dimension go together."""
        return (PointsRow, self.dimension)

    @property
    def dimension(self) -> int:
        """2 or 3."""
        return 3 if self.positions.ndim == 2 and self.positions.shape[1] == 3 else 2

    @property
    def nbytes(self) -> int:
        """Bytes of positions the row holds."""
        return int(self.positions.nbytes)

    def archetype(self) -> Any:
        """The row as one ``log`` call's archetype."""
        return (rr.Points3D if self.dimension == 3 else rr.Points2D)(self.positions)

    @staticmethod
    def columns(rows: Sequence[PointsRow]) -> Any:
        """The positions of ``rows`` (one dimension), one list per row."""
        dimension = rows[0].dimension
        positions = [np.asarray(row.positions, dtype=np.float32).reshape(-1, dimension)
                     for row in rows]
        archetype = rr.Points3D if dimension == 3 else rr.Points2D
        return archetype.columns(positions=np.concatenate(positions)).partition(
            [len(p) for p in positions])


@dataclass(frozen=True, slots=True)
class ClearRow:
    """A non-recursive clear: the entity shows nothing from this time on."""

    def key(self) -> tuple[Any, ...]:
        """Every clear goes with the others."""
        return (ClearRow,)

    @property
    def nbytes(self) -> int:
        """A clear holds no data."""
        return 0

    def archetype(self) -> Any:
        """The row as one ``log`` call's archetype."""
        return rr.Clear(recursive=False)

    @staticmethod
    def columns(rows: Sequence[ClearRow]) -> Any:
        """One non-recursive clear per row."""
        return rr.Clear.columns(is_recursive=[False] * len(rows))


Row = ImageRow | PointsRow | ClearRow


@dataclass
class _Batch:
    key: tuple[Any, ...]
    kind: type[ImageRow] | type[PointsRow] | type[ClearRow]
    times: list[Times]
    rows: list[Any]
    nbytes: int = 0


class ColumnBatcher:
    """Gathers rows per entity and sends each entity's batch with ``send_columns`` when it
    is full (:data:`MAX_ROWS`), when it is the largest one while the bytes held pass
    :data:`MAX_BATCH_BYTES`, when the entity gets a row of another kind or timelines, and
    on :meth:`flush`."""

    def __init__(self, rec: rr.RecordingStream, *, max_rows: int = MAX_ROWS,
                 max_bytes: int = MAX_BATCH_BYTES) -> None:
        self.rec = rec
        self._max_rows, self._max_bytes = max_rows, max_bytes
        self._batches: dict[str, _Batch] = {}
        self._held = 0  # bytes of the rows not yet sent

    def add(self, entity: str, times: Times, row: Row) -> None:
        """Queue ``row`` for ``entity`` at ``times``."""
        key = (row.key(), times[1] is None, times[2] is None)
        batch = self._batches.get(entity)
        if batch is not None and batch.key != key:
            self.flush_entity(entity)
            batch = None
        if batch is None:
            batch = self._batches[entity] = _Batch(key, type(row), [], [])
        batch.times.append(times)
        batch.rows.append(row)
        batch.nbytes += row.nbytes
        self._held += row.nbytes
        if len(batch.rows) >= self._max_rows:
            self.flush_entity(entity)
        while self._held > self._max_bytes:  # the largest batches go: small ones fill up
            self.flush_entity(max(self._batches, key=lambda name: self._batches[name].nbytes))

    def flush_entity(self, entity: str) -> None:
        """Send ``entity``'s queued rows (before anything else is logged to it)."""
        batch = self._batches.pop(entity, None)
        if batch is None:
            return
        self._held -= batch.nbytes
        self.rec.send_columns(entity, indexes=_indexes(batch.times),
                              columns=batch.kind.columns(batch.rows))

    def flush(self) -> None:
        """Send every queued row."""
        for entity in list(self._batches):
            self.flush_entity(entity)


def _indexes(times: Sequence[Times]) -> list[Any]:
    """The time columns of rows that all have (or all lack) a stamp and a replay time."""
    def column(timeline: str, values: Sequence[int | None]) -> Any:
        return rr.TimeColumn(timeline, timestamp=np.array(values, dtype="datetime64[ns]"))

    indexes = [column(LOG_TIME, [t[0] for t in times])]
    if times[0][1] is not None:
        indexes.append(column(STAMP_TIME, [t[1] for t in times]))
    if times[0][2] is not None:
        indexes.append(column(REPLAY_TIME, [t[2] for t in times]))
    return indexes
