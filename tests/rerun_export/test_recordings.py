"""Several logs in one ``view``: related logs share a recording, unrelated ones get their
own (same application id, own recording id, own timelines), read back with rerun's loader
and dataframe API."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from rerun.chunk import RrdReader
from rerun.error_utils import RerunWarning

from replay import Image, Text, open_writer
from replay.camera import CameraModel
from rerun_export import view_logs
from tests.rrd import Receiver, rerun_cli

T0 = 1_700_000_000_000_000_000
HOUR_NS = 3600 * 10**9


def camera_log(path: Path, namespace: str, start_ns: int, frames: int = 3) -> Path:
    """``frames`` 8x8 mono images of one camera at 10 Hz from ``start_ns``, and a note on a
    topic every such log has (text names no camera: it relates no logs)."""
    with open_writer(path) as writer:
        writer.write("/camlog/notes", Text(f"{namespace} from {start_ns}"),
                     log_time_ns=start_ns)
        for i in range(frames):
            stamp = start_ns + i * 100_000_000
            writer.write(f"{namespace}/image_raw",
                         Image(stamp, namespace.strip("/") + "_optical_frame", "mono8",
                               np.full((8, 8), i, np.uint8)), log_time_ns=stamp)
    return path


def image_stamps(path: Path) -> dict[str, list[int]]:
    """Per recording (in file order): the header stamps of every image entity's rows,
    queried with rerun's dataframe API."""
    reader = RrdReader(path)
    out: dict[str, list[int]] = {}
    for entry in reader.recordings():
        store = reader.stream(store=entry).collect()
        table = store.reader(index="header_stamp", contents="/world/**").to_arrow_table()
        for name in table.column_names:
            if name.endswith(":Image:buffer"):
                rows = table.filter(pa.compute.is_valid(table.column(name)))
                entity = name.split(":")[0]
                out[f"{entry.recording_id} {entity}"] = \
                    rows.column("header_stamp").cast(pa.int64()).to_pylist()
    return out


@pytest.mark.slow
def test_unrelated_logs_keep_their_own_recordings(tmp_path: Path) -> None:
    morning = camera_log(tmp_path / "morning.mcap", "/front", T0)
    evening = camera_log(tmp_path / "evening.mcap", "/front", T0 + 10 * HOUR_NS, frames=2)
    other_rig = camera_log(tmp_path / "rig.mcap", "/rear", T0)
    out = tmp_path / "three.rrd"
    result = view_logs([morning, evening, other_rig], output=out, progress=False)
    assert result.recordings == 3 and result.messages == 11
    entries = RrdReader(out).recordings()
    assert {e.application_id for e in entries} == {"camlog"}
    assert len({e.recording_id for e in entries}) == 3
    # in input order: the viewer opens the first log's recording, the layout's first tab
    assert image_stamps(out)[f"{entries[0].recording_id} /world/front/image"][0] == T0
    stamps = sorted((times[0], key.split()[1], times) for key, times in image_stamps(out).items())
    # each log on its own: the evening's frames do not stretch the morning's timeline
    assert [(entity, times) for _, entity, times in stamps] == [
        ("/world/front/image", [T0, T0 + 100_000_000, T0 + 200_000_000]),
        ("/world/rear/image", [T0, T0 + 100_000_000, T0 + 200_000_000]),
        ("/world/front/image", [T0 + 10 * HOUR_NS, T0 + 10 * HOUR_NS + 100_000_000]),
    ]
    assert len(RrdReader(out).blueprints()) >= 1
    verify = rerun_cli("rrd", "verify", str(out), cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_one_log_is_one_recording_as_before(tmp_path: Path) -> None:
    log = camera_log(tmp_path / "one.mcap", "/front", T0)
    result = view_logs([log], output=tmp_path / "one.rrd", progress=False)
    assert result.recordings == 1
    assert len(RrdReader(tmp_path / "one.rrd").recordings()) == 1


def test_overlapping_logs_of_one_camera_share_a_recording(tmp_path: Path) -> None:
    first = camera_log(tmp_path / "a.mcap", "/front", T0)
    more = tmp_path / "b.mcap"
    with open_writer(more) as writer:  # the same camera's calibration, at the same time
        for i in range(3):
            stamp = T0 + i * 100_000_000
            info = CameraModel.ideal(8, 8, 0.6).camera_info(stamp_ns=stamp,
                                                            frame_id="front_optical_frame")
            writer.write("/front/camera_info", info, log_time_ns=stamp)
    out = tmp_path / "merged.rrd"
    result = view_logs([first, more], output=out, progress=False)
    assert result.recordings == 1 and result.messages == 4 + 3
    assert len(RrdReader(out).recordings()) == 1 and result.cameras == ["/front"]


def test_a_viewer_receives_each_recording(tmp_path: Path) -> None:
    morning = camera_log(tmp_path / "morning.mcap", "/front", T0)
    other_rig = camera_log(tmp_path / "rig.mcap", "/rear", T0)
    receiver = Receiver(tmp_path)  # a headless rerun that saves what it receives
    try:
        result = view_logs([morning, other_rig], connect=receiver.url, progress=False)
        deadline, received = time.monotonic() + 30, received_images(receiver.path)
        while len(received) < 2 and time.monotonic() < deadline:
            time.sleep(0.3)
            received = received_images(receiver.path)
    finally:
        receiver.stop()
    assert result.recordings == 2 and result.output is None
    # two recordings (application camlog), one camera each, three frames each
    assert sorted(received.values()) == [("camlog", "/world/front/image", 3),
                                         ("camlog", "/world/rear/image", 3)]


def received_images(path: Path) -> dict[str, tuple[str, str, int]]:
    """recording id -> (application id, image entity, frames) of an .rrd being written."""
    out = {}
    with warnings.catch_warnings():  # the file has no footer while it is written
        warnings.filterwarnings("ignore", "RRD file has no footer", RerunWarning)
        try:
            reader = RrdReader(path)
            for entry in reader.recordings():
                for chunk in reader.stream(store=entry):
                    if chunk.entity_path.endswith("/image"):
                        _, _, frames = out.get(entry.recording_id, ("", "", 0))
                        out[entry.recording_id] = (entry.application_id, chunk.entity_path,
                                                   frames + chunk.num_rows)
        except (OSError, ValueError, RuntimeError):
            return {}
    return out
