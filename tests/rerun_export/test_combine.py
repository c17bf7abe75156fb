"""Recordings combined as a stream: every recording kept apart in one verified ``.rrd``,
the combiner fed no faster than it writes, and its failure as one error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import rerun as rr
from rerun.chunk import RrdReader

from rerun_export import combine
from rerun_export.combine import combine_recordings
from rerun_export.errors import ViewerError
from tests.rrd import rerun_cli


def part(path: Path, recording_id: str, frames: int = 4) -> Path:
    """A recording of ``frames`` noisy 64x64 images (they do not compress away)."""
    rec = rr.RecordingStream("camlog", recording_id=recording_id)
    rec.save(path)
    rng = np.random.default_rng(len(recording_id))
    for i in range(frames):
        rec.set_time("frame", sequence=i)
        rec.log("cam/image", rr.Image(rng.integers(0, 255, (64, 64), dtype=np.uint8)))
    rec.flush()
    rec.disconnect()
    return path


@pytest.mark.slow
def test_recordings_stay_apart_in_one_verified_file(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(combine, "BLOCK_BYTES", 4096)  # many blocks, each paced
    monkeypatch.setattr(combine, "IN_FLIGHT_BYTES", 4096)
    parts = [part(tmp_path / f"{i}.rrd", f"rec-{i}", frames=4 + i) for i in range(3)]
    out = tmp_path / "all.rrd"
    combine_recordings(parts, out)
    reader = RrdReader(out)
    assert [e.recording_id for e in reader.recordings()] == ["rec-0", "rec-1", "rec-2"]
    rows = [reader.stream(store=e).collect().reader(index="frame").to_arrow_table().num_rows
            for e in reader.recordings()]
    assert rows == [4, 5, 6]
    verify = rerun_cli("rrd", "verify", str(out), cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr


def test_a_part_that_is_no_recording_is_one_error(tmp_path: Path) -> None:
    good = part(tmp_path / "good.rrd", "good")
    bad = tmp_path / "bad.rrd"
    bad.write_bytes(b"not an rrd at all" * 100)
    with pytest.raises(ViewerError, match="cannot combine the recordings: rerun rrd filter") \
            as caught:
        combine_recordings([bad, good], tmp_path / "out.rrd")
    assert "\n" not in str(caught.value)
