"""Rows sent as columns store what one ``log`` call per row stores, read back with rerun's
dataframe API: the same rows per entity and timeline, clears in their place."""

from __future__ import annotations

import contextlib
import functools
import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import ChunkStore, RrdReader

from rerun_export import emitter as emitter_module
from rerun_export.columns import BUFFER_TYPE, ClearRow, ColumnBatcher, ImageRow, PointsRow
from rerun_export.emitter import Emitter
from rerun_export.logger import LoggerOptions, SceneLogger
from rerun_export.sink import RecordingSink
from rerun_export.view import open_logs

INDEXES = ("log_time", "header_stamp")


def store_of(path: Path) -> ChunkStore:
    reader = RrdReader(path)
    (recording,) = reader.recordings()
    return reader.stream(store=recording).collect()


def tables(path: Path) -> dict[str, list[dict[str, Any]]]:
    """Per timeline: every row of the recording (clears included), sorted."""
    store = store_of(path)
    out = {}
    for index in INDEXES:
        table = store.reader(index=index, contents="/**",
                             include_tombstone_columns=True).to_arrow_table()
        columns = sorted(c for c in table.column_names if c in INDEXES or c.startswith("/"))
        table = table.select(columns)
        for position, column in enumerate(table.columns):
            if column.type == IMAGE_BUFFERS:
                table = table.set_column(position, table.field(position).name,
                                         digests(column))
        rows = table.to_pylist()
        out[index] = sorted(rows, key=repr)
    return out


#: an image buffer column: per row, a list of buffers of bytes
IMAGE_BUFFERS = pa.list_(pa.field("item", pa.list_(pa.field("item", pa.uint8(),
                                                            nullable=False))))


def digests(column: pa.ChunkedArray) -> pa.Array:
    """An image buffer column with each buffer's bytes as their SHA-256: rows compare (and
    sort) by the same bytes without a Python int per pixel."""
    cells: list[list[str | None] | None] = []
    for cell in column.combine_chunks():
        if not cell.is_valid:
            cells.append(None)
            continue
        cells.append([hashlib.sha256(buffer.values.to_numpy(zero_copy_only=False).tobytes()
                                     ).hexdigest() if buffer.is_valid else None
                      for buffer in cell.values])
    return pa.array(cells, type=pa.list_(pa.string()))


def record(path: Path, feed: Callable[[Emitter], None], *, columns: bool) -> None:
    rec = rr.RecordingStream("camlog-test", recording_id="same")
    rec.save(path)
    rec.set_log_time_enabled(False)
    rec.set_log_tick_enabled(False)
    emitter = Emitter(rec, columns=columns)
    feed(emitter)
    emitter.close()
    rec.flush()
    rec.disconnect()


def feed_rows(out: Emitter) -> None:
    """Images changing size midway, 16-bit ones (some not contiguous), points (one frame
    with none), clears and points on one entity at one time, a frame without a stamp, and a
    box log call between rows."""
    rng = np.random.default_rng(3)
    t0 = 1_700_000_000_000_000_000
    for i in range(11):
        log_ns, stamp_ns = t0 + i * 10_000_000, t0 + i * 10_000_000 - 5_000
        out.at(log_ns, None if i == 4 else stamp_ns, None)
        size = (6, 8) if i < 7 else (5, 9)
        out.emit("cam/image", ImageRow(rng.integers(0, 255, size, dtype=np.uint8), "L"))
        out.emit("cam/rgb", ImageRow(rng.integers(0, 255, (3, 4, 3), dtype=np.uint8), "BGR",
                                     draw_order=-7.0))
        deep = rng.integers(0, 65535, (4, 6), dtype=np.uint16)
        out.emit("cam/mono16", ImageRow(deep[:, ::2] if i % 2 else deep, "L"))  # strided too
        if i % 3 == 0:
            out.emit("cam/corners", ClearRow(), count=False)
        out.emit("cam/corners", PointsRow(rng.random((0 if i == 5 else 4, 2))))
        if i == 6:
            out.emit("cam/corners", rr.Boxes2D(mins=[[0, 0]], sizes=[[8, 6]]))
        out.emit("cam/truth", PointsRow(rng.random((3, 2))))


@pytest.mark.slow
def test_columns_store_what_a_log_call_per_row_stores(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    # small batches: every reason to send a batch happens
    monkeypatch.setattr(emitter_module, "ColumnBatcher",
                        functools.partial(ColumnBatcher, max_rows=3))
    by_row, by_column = tmp_path / "rows.rrd", tmp_path / "columns.rrd"
    record(by_row, feed_rows, columns=False)
    record(by_column, feed_rows, columns=True)
    expected = tables(by_row)
    assert len(expected["log_time"]) == 11 and len(expected["header_stamp"]) == 10
    assert tables(by_column) == expected


def test_a_batch_is_sent_when_the_pixels_held_pass_the_limit(tmp_path: Path) -> None:
    sent: list[tuple[str, int]] = []

    class Recording:
        def send_columns(self, entity: str, *, indexes: Any, columns: Any) -> None:
            sent.append((entity, len(indexes[0].as_arrow_array())))

    batcher = ColumnBatcher(Recording(), max_rows=100, max_bytes=1000)  # type: ignore[arg-type]
    image = np.zeros((20, 20), np.uint8)  # 400 bytes
    for i in range(3):
        batcher.add("a", (i, i, None), ImageRow(image, "L"))
    assert sent == [("a", 3)]  # 1200 bytes held: sent
    batcher.add("a", (3, None, None), ImageRow(image, "L"))
    batcher.add("a", (4, 4, None), ImageRow(image, "L"))  # a stamp again: a batch of its own
    assert sent == [("a", 3), ("a", 1)]
    batcher.flush()
    assert sent == [("a", 3), ("a", 1), ("a", 1)]


def test_only_the_largest_batches_go_when_the_bytes_pass_the_limit() -> None:
    sent: list[tuple[str, int]] = []

    class Recording:
        def send_columns(self, entity: str, *, indexes: Any, columns: Any) -> None:
            sent.append((entity, len(indexes[0].as_arrow_array())))

    batcher = ColumnBatcher(Recording(), max_rows=100, max_bytes=1000)  # type: ignore[arg-type]
    image, points = np.zeros((20, 20), np.uint8), np.zeros((4, 2), np.float32)  # 400, 32 bytes
    for i in range(3):
        batcher.add("image", (i, i, None), ImageRow(image, "L"))
        batcher.add("corners", (i, i, None), PointsRow(points))
    # the image batch went; the points keep filling their batch (fewer, larger chunks)
    assert sent == [("image", 3)]
    batcher.flush()
    assert sent == [("image", 3), ("corners", 3)]


def test_a_calibration_log_views_the_same_in_columns(mono_calibration_log: Path,
                                                     tmp_path: Path) -> None:
    """Held poses, overlays cleared by the next image, ground truth: the whole export."""
    outputs = {}
    for columns in (False, True):
        out = outputs[columns] = tmp_path / f"{columns}.rrd"
        with contextlib.ExitStack() as stack:
            session = open_logs(stack, [mono_calibration_log], topics=None, start_s=None,
                                end_s=None, recover=False)
            with RecordingSink(output=out, recording_id="same") as sink:
                logger = SceneLogger(sink.rec, session.plan, LoggerOptions(),
                                     decode=session.decode, flush=sink.flush, columns=columns)
                logger.log_static()
                for raw in session.messages():
                    logger.log(raw)
                logger.close()
    expected = tables(outputs[False])
    corners = "/raw/simple_camera/calibration/corners:Points2D:positions"
    assert sum(row.get(corners) is not None for row in expected["header_stamp"]) >= 30
    assert tables(outputs[True]) == expected


def test_the_image_buffer_column_has_reruns_own_type() -> None:
    # a column of another type would go through rerun's slow per-image conversion
    assert BUFFER_TYPE == rr.components.ImageBufferBatch._ARROW_DATATYPE
