"""A held board pose keeps its calibration overlays on every frame of the hold, read back
with rerun's dataframe API (a latest-at query over the rows of the .rrd)."""

from __future__ import annotations

import bisect
from pathlib import Path

import pyarrow as pa
from rerun.chunk import ChunkStore, RrdReader

from replay.export import view_logs

CAMERA = "/world/simple_camera"
CORNERS = f"{CAMERA}/calibration/corners"


def rows(store: ChunkStore, entity: str) -> pa.Table:
    """The rows logged at ``entity`` on the header_stamp timeline, clears included."""
    return store.reader(index="header_stamp", contents=entity,
                        include_tombstone_columns=True).sort("header_stamp").to_arrow_table()


def stamps_ns(table: pa.Table) -> list[int]:
    return table.column("header_stamp").cast(pa.int64()).to_pylist()  # type: ignore[no-any-return]


def test_a_held_poses_corners_stay_on_all_its_frames(mono_calibration_log: Path,
                                                     tmp_path: Path) -> None:
    out = tmp_path / "held.rrd"
    view_logs([mono_calibration_log], output=out, progress=False)
    reader = RrdReader(out)
    (recording,) = reader.recordings()
    store = reader.stream(store=recording).collect()

    images = rows(store, f"{CAMERA}/image")
    image_stamps = stamps_ns(images)
    buffers = images.column(f"{CAMERA}/image:Image:buffer").to_pylist()
    assert len(image_stamps) == 120
    # the hold each frame belongs to: the first frame of its run of identical images
    hold_start = []
    for i, buffer in enumerate(buffers):
        same = i > 0 and buffer == buffers[i - 1]
        hold_start.append(hold_start[-1] if same else image_stamps[i])

    corners = rows(store, CORNERS)
    corner_stamps = stamps_ns(corners)
    positions = corners.column(f"{CORNERS}:Points2D:positions").to_pylist()
    views = {s: p for s, p in zip(corner_stamps, positions, strict=True) if p}
    assert len(views) > 20 and set(views) <= set(hold_start)

    def shown(stamp_ns: int) -> list[list[float]]:
        """What the viewer draws at ``stamp_ns``: the latest row at or before it (a clear
        logs empty positions)."""
        at = bisect.bisect_right(corner_stamps, stamp_ns) - 1
        return positions[at] or [] if at >= 0 else []

    held = 0
    for stamp, start in zip(image_stamps, hold_start, strict=True):
        assert shown(stamp) == views.get(start, []), f"frame {stamp} of the hold at {start}"
        held += stamp != start and start in views
    assert held > len(views)  # most holds last 2-4 frames: their later frames show corners
