"""The stereo peers are given what camlog paired and recover a rendered rig of two
free-running cameras.

3 s of ``stereo_heldout`` seed 0: the right camera shoots 7 ms after the left (with jitter and
dropped frames) and the board jumps from held pose to held pose, once between a left frame and
its right partner. Paired across that jump, ``stereoCalibrate`` was 60° off on this log.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from benchmarks.calibrate_speed import calibrate, parse_flags
from benchmarks.calibration_truth import opencv_models, rotation_deg, true_right_from_left
from benchmarks.mrcal_run import request
from benchmarks.opencv_stereo_log import calibrate_pair
from camlog.calibrate.flow import CalibrationRun
from recorder.record import record
from recorder.scenario import load_scenario

FLAGS = "--left /heldout/left --right /heldout/right -s 7x6 -q 0.01 --approximate 0.02"
#: a rig's rotation from 4-6 held poses of a 7x6 board, 1 cm squares at 15-32 cm
ROTATION_DEG = 0.5

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("stereo_heldout") / "stereo_heldout.mcap"
    record(load_scenario("stereo_heldout", {"duration_s": 3.0, "seed": 0}), path,
           progress=False)
    return path


@pytest.fixture(scope="module")
def run(log: Path, tmp_path_factory: pytest.TempPathFactory) -> CalibrationRun:
    return calibrate(log, FLAGS, tmp_path_factory.mktemp("out"), report=False)


def test_every_pair_the_peers_are_given_shows_one_board_pose(run: CalibrationRun) -> None:
    rig, (left, right) = run.solved.rig, run.cameras
    truth = true_right_from_left(run)
    assert truth is not None and len(rig.pairs) >= 3
    left_truth = left.views.true_camera_from_target["checkerboard"]
    right_truth = right.views.true_camera_from_target["checkerboard"]
    for lv, rv in rig.pairs:
        for lf in rig.frames_of[lv]:
            for rf in rig.frames_of[rv]:
                seen_left = left_truth[left.views.frames[lf].stamp_ns]
                seen_right = right_truth[right.views.frames[rf].stamp_ns]
                # the board the right camera saw is the one the left saw, moved by the rig
                np.testing.assert_allclose(seen_right[:3, 3], (truth @ seen_left)[:3, 3],
                                           atol=1e-6)


def test_the_harness_stereo_calibrate_recovers_the_rig(run: CalibrationRun, log: Path) -> None:
    _models, right_from_left = opencv_models(run, parse_flags(log, FLAGS).board())
    truth = true_right_from_left(run)
    assert right_from_left is not None and truth is not None
    assert rotation_deg(right_from_left[:3, :3], truth[:3, :3]) < ROTATION_DEG
    baseline = float(np.linalg.norm(truth[:3, 3]))
    assert math.isclose(float(np.linalg.norm(right_from_left[:3, 3])), baseline, rel_tol=0.02)


def test_the_users_script_recovers_the_rig(run: CalibrationRun, log: Path) -> None:
    found = calibrate_pair(log, left_topic="/heldout/left/image_raw",
                           right_topic="/heldout/right/image_raw", size=(7, 6), square_m=0.01,
                           slop_s=0.02)
    truth = true_right_from_left(run)
    assert truth is not None and found.pairs >= 3
    assert rotation_deg(found.rotation, truth[:3, :3]) < ROTATION_DEG
    assert found.rms_px < 0.2


def test_mrcal_is_given_every_pair_camlog_made(run: CalibrationRun, log: Path) -> None:
    board = parse_flags(log, FLAGS).board()
    sent = request(run, board, lensmodel="LENSMODEL_OPENCV5", focal_px=1000.0)
    left, right = (set(camera["frames"]) for camera in sent["cameras"])
    rig = run.solved.rig
    for lv, rv in rig.pairs:
        for lf, rf in zip(rig.frames_of[lv], rig.frames_of[rv], strict=True):
            # a pair is one mrcal frame number, seen by both cameras
            assert str(lf) in left and str(lf) in right, (lf, rf)
    assert len(left & right) >= len(rig.pairs)
