"""``camlog resync --estimate-offset`` / ``--offset`` on logs whose right camera stamps 17 ms
late: measured from a waved board and from natural features of a moving rig, and frames
paired as their true exposure times pair them."""

from __future__ import annotations

import json
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from processors.resync import default_slop_ns, pair_stamps
from replay import Image, open_reader
from replay.records import ResyncStats, Scenario, TimeOffset

pytestmark = pytest.mark.slow

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"
CAMERAS = ["--left", LEFT, "--right", RIGHT]
BOARD = ["-s", "7x6", "-q", "0.01"]
LATENCY_MS = 17.0


def _record(spec: Path | str, out: Path, *options: str) -> Path:
    assert main(["record", str(spec), "-o", str(out), "--resolution", "320x240",
                 "--no-progress", *options]) == 0
    return out


@pytest.fixture(scope="module")
def board_log(late_board_log: Path) -> Path:
    """The waved board, the right camera stamping 17 ms late (20 s at 320x240)."""
    return late_board_log


def _run(*argv: str) -> list[str]:
    printed = StringIO()
    with redirect_stdout(printed):
        assert main(list(argv)) == 0
    return printed.getvalue().splitlines()


def test_the_board_shows_the_offset_within_a_millisecond(board_log: Path,
                                                          tmp_path: Path) -> None:
    result = tmp_path / "offset.json"
    lines = _run("resync", str(board_log), *CAMERAS, *BOARD, "--estimate-offset",
                 "--offset-file", str(result), "--no-progress")
    offset = TimeOffset.from_json_text(result.read_text())
    assert abs(offset.offset_ms - LATENCY_MS) < 1.0
    assert abs(offset.offset_ms - LATENCY_MS) < 5 * offset.std_ms + 0.05
    assert offset.method == "board" and offset.first == LEFT and offset.second == RIGHT
    assert offset.frames > 0.5 * offset.frames_fitted > 300  # both cameras' moving frames
    assert offset.second_from_first is not None
    np.testing.assert_allclose(offset.second_from_first[:3, 3], [-0.02, 0, 0], atol=5e-4)
    assert lines[0].startswith(f"time offset {RIGHT} - {LEFT}: +{offset.offset_ms:.3f} ± ")
    assert lines[-1].startswith(f"wrote {result}")


def _true_pairs(log: Path) -> list[tuple[int, int]]:
    """(left frame, right frame) by the frames' true exposure times (stamp less latency)."""
    with open_reader(log) as reader:
        stamps: dict[str, list[int]] = {LEFT: [], RIGHT: []}
        scenario = None
        for raw in reader.raw_messages():
            message = reader.decode(raw)
            if raw.topic == "/camlog/scenario":
                scenario = Scenario.from_message(message)
            elif isinstance(message, Image):
                stamps[raw.topic.rpartition("/")[0]].append(message.stamp_ns)
    assert scenario is not None
    exposed = {ns: np.array(s) - scenario.latency_ns(camera)
               for ns, s in stamps.items()
               for camera in (scenario.camera_for(ns),) if camera is not None}
    pairing = pair_stamps(exposed[LEFT], exposed[RIGHT],
                          slop_ns=default_slop_ns(exposed[LEFT], exposed[RIGHT]))
    return list(zip(pairing.left_index.tolist(), pairing.right_index.tolist(), strict=True))


def _written_pairs(log: Path, synced: Path) -> list[tuple[int, int]]:
    """(left frame, right frame) of every pair resync wrote, by matching their pixels."""
    with open_reader(log) as reader:
        index = {ns: {} for ns in (LEFT, RIGHT)}  # type: dict[str, dict[bytes, int]]
        for raw in reader.raw_messages([f"{LEFT}/image_raw", f"{RIGHT}/image_raw"]):
            image = reader.decode(raw)
            assert isinstance(image, Image)
            side = index[raw.topic.rpartition("/")[0]]
            side[image.pixels.tobytes()] = len(side)
    out: dict[int, list[int]] = {}
    with open_reader(synced) as reader:
        for raw in reader.raw_messages(["/stereo_sync/left/image_raw",
                                        "/stereo_sync/right/image_raw"]):
            image = reader.decode(raw)
            assert isinstance(image, Image)
            side = LEFT if "/left/" in raw.topic else RIGHT
            out.setdefault(image.stamp_ns, []).append(index[side][image.pixels.tobytes()])
    return sorted((pair[0], pair[1]) for pair in out.values())


def test_resync_by_the_estimate_pairs_frames_as_their_exposures_do(
        board_log: Path, tmp_path: Path) -> None:
    synced = tmp_path / "synced.mcap"
    lines = _run("resync", str(board_log), "-o", str(synced), *CAMERAS, *BOARD,
                 "--offset", "estimated", "--no-progress")
    assert any(line.startswith("right stamps moved by -17.") for line in lines)
    written = _written_pairs(board_log, synced)
    assert written == _true_pairs(board_log)
    with open_reader(synced) as reader:
        (raw,) = list(reader.raw_messages(["/stereo_sync/stats"]))
        stats = ResyncStats.from_message(reader.decode(raw))
    assert stats.time_offset is not None and stats.right_stamps_moved_ns is not None
    assert abs(stats.right_stamps_moved_ns / 1e6 + LATENCY_MS) < 1.0
    assert stats.offset_right_minus_left_ns is not None
    assert abs(stats.offset_right_minus_left_ns.median) < 1_000_000  # pairs now agree
    # the estimate went beside the output; given back, it pairs the same frames
    offset_file = synced.with_name("synced_offset.json")
    again = tmp_path / "again.mcap"
    _run("resync", str(board_log), "-o", str(again), *CAMERAS, "--offset", str(offset_file))
    assert _written_pairs(board_log, again) == written
    # stamps as they are pair each left frame with the right frame exposed one before
    plain = tmp_path / "plain.mcap"
    _run("resync", str(board_log), "-o", str(plain), *CAMERAS)
    assert _written_pairs(board_log, plain) != written


def test_a_held_board_does_not_show_it(tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    held = _record("stereo_checkerboard", tmp_path / "held.mcap", "--duration", "4",
                   "--latency", "right:17")
    assert main(["resync", str(held), *CAMERAS, *BOARD, "--estimate-offset",
                 "--offset-file", str(tmp_path / "o.json"), "--no-progress"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a held one does not" in err[0]
    assert not (tmp_path / "o.json").exists()


def test_natural_features_of_a_moving_rig_show_it(tmp_path: Path) -> None:
    log = _record("stereo_moving_rig", tmp_path / "rig.mcap", "--duration", "4",
                  "--latency", f"right:{LATENCY_MS:g}")
    result = tmp_path / "rig_offset.json"
    _run("resync", str(log), *CAMERAS, "--estimate-offset", "--offset-file", str(result),
         "--no-progress")
    offset = json.loads(result.read_text())
    assert offset["method"] == "features" and "second_from_first" not in offset
    assert abs(offset["offset_ms"] - LATENCY_MS) < 0.5
    assert offset["frames"] >= 20
