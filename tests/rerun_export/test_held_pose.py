"""A held board pose keeps its calibration overlays on every frame of the hold, read back
with rerun's dataframe API (a latest-at query over the rows of the .rrd)."""

from __future__ import annotations

import bisect
from pathlib import Path

import numpy as np
import pyarrow as pa
from rerun.chunk import ChunkStore, RrdReader

from replay import Image, open_reader, open_writer
from replay.records import ViewResiduals
from rerun_export import view_logs

CAMERA = "/raw/simple_camera"  # a calibrated (distorted) camera's raw image and overlays
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
    # calibrate records where each view's hold ends: the hold's last frame
    last = dict(zip(hold_start, image_stamps, strict=True))
    with open_reader(mono_calibration_log) as log:
        records = [ViewResiduals.from_message(m.message)
                   for m in log.messages(["/simple_camera/calibration/residuals"])]
    assert {r.stamp_ns: r.until_ns for r in records} == {s: last[s] for s in views}


def test_a_noisy_held_pose_keeps_its_corners_until_its_view_ends(tmp_path: Path) -> None:
    """Sensor noise makes every frame of a hold distinct: the view's ``until_ns`` (what
    calibrate records) keeps its corners up to the hold's last frame, and no further."""
    t0, step = 1_700_000_000_000_000_000, 100_000_000
    stamps = [t0 + i * step for i in range(6)]
    rng = np.random.default_rng(0)
    corners = np.array([[10.0, 12.0], [30.0, 12.0], [10.0, 30.0]])
    log = tmp_path / "noisy.mcap"
    with open_writer(log) as writer:
        for i, stamp in enumerate(stamps):  # frames 0-2 hold one pose, 3-5 move
            pixels = rng.integers(0, 255, (48, 64), dtype=np.uint8)
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", pixels),
                         log_time_ns=stamp)
            if i in (0, 3):
                until = stamps[2] if i == 0 else None
                view = ViewResiduals(stamp, "cam", 0.05, corners + i, np.zeros((3, 2)),
                                     until_ns=until)
                writer.write("/cam/calibration/residuals", view.to_message(),
                             log_time_ns=stamp)
    out = tmp_path / "noisy.rrd"
    view_logs([log], output=out, progress=False)
    reader = RrdReader(out)
    (recording,) = reader.recordings()
    store = reader.stream(store=recording).collect()
    entity = "/world/cam/calibration/corners"
    table = rows(store, entity)
    corner_stamps = stamps_ns(table)
    positions = table.column(f"{entity}:Points2D:positions").to_pylist()

    def shown(stamp_ns: int) -> int:
        at = bisect.bisect_right(corner_stamps, stamp_ns) - 1
        return len(positions[at] or []) if at >= 0 else 0

    assert [shown(s) for s in stamps] == [3, 3, 3, 3, 0, 0]
