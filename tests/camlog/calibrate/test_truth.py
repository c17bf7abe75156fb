"""The true error in a simulated log's summary is the error the uncertainty predicts, measured
against the board poses the simulator logged."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from camlog.calibrate.flow import CalibrationRun, calibrate_log
from camlog.golden.run import golden_dir
from camlog.requests.calibrate import CalibrateRequest
from processors.calibration.board import Board
from processors.calibration.rotation import rigid_fit
from processors.calibration.uncertainty import error_against
from replay import open_reader
from replay.geometry import transform_from_pose
from replay.messages import PoseStamped
from replay.records import Scenario
from replay.topics import SCENARIO

LOG = golden_dir() / "mono_checkerboard-seed0-640x480-f240.mcap"
NAMESPACE = "/simple_camera"
BOARD = Board(7, 6, 0.01)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> CalibrationRun:
    return calibrate_log(CalibrateRequest(
        log=LOG, size="7x6", square=0.01, camera=(NAMESPACE,),
        output=tmp_path_factory.mktemp("truth") / "out", progress=False, report=False))


def logged_truth(path: Path) -> tuple[Scenario, dict[int, np.ndarray]]:
    """The scenario record and the board's true ``camera_from_target`` per image stamp."""
    poses: dict[int, np.ndarray] = {}
    scenario = None
    with open_reader(path) as reader:
        topic = f"{NAMESPACE}/ground_truth/checkerboard"
        for message in reader.messages([SCENARIO, topic]):
            if isinstance(message.message, PoseStamped):
                pose = message.message
                poses[pose.stamp_ns] = transform_from_pose(pose.position_m,
                                                           pose.orientation_xyzw)
            else:
                scenario = Scenario.from_message(message.message)
    assert scenario is not None and len(poses) >= 200
    return scenario, poses


def test_true_error_is_error_against_the_logged_board_poses(run: CalibrationRun) -> None:
    """Each instant's true pose built here from its first frame's logged pose, the board's
    points matched to the target's by where the true camera images them."""
    scenario, poses = logged_truth(LOG)
    (camera,), (target,) = scenario.cameras, scenario.targets
    model = camera.model()
    in_target = np.asarray(target.corners_in_target, dtype=np.float64)
    points = BOARD.points_in_board()
    solved = run.solved
    truth: dict[int, np.ndarray] = {}
    for view, frames in zip(solved.rig.views, solved.rig.frames_of, strict=True):
        camera_from_target = poses[run.cameras[0].views.frames[frames[0]].stamp_ns]
        imaged = model.project(in_target @ camera_from_target[:3, :3].T
                               + camera_from_target[:3, 3])
        nearest = np.argmin(np.linalg.norm(view.corners_px[:, None] - imaged[None], axis=2),
                            axis=1)
        assert len(set(nearest.tolist())) == len(nearest)
        truth[view.instant] = camera_from_target @ rigid_fit(points[view.point_ids],
                                                             in_target[nearest])
    # the solver agrees with these poses to a small fraction of a square
    for instant, estimated in solved.joint.reference_from_board.items():
        assert np.abs(estimated[:3, 3] - truth[instant][:3, 3]).max() < 1e-3
        assert np.abs(estimated[:3, :3] - truth[instant][:3, :3]).max() < 2e-3
    u = run.summary.cameras[0].uncertainty
    assert u is not None and u.true_error_median_px is not None
    statistics = run.statistics[0]
    for umap, median, worst in (
            (statistics.uncertainty, u.true_error_median_px, u.true_error_worst_px),
            (statistics.rays_uncertainty, u.rays_true_error_median_px,
             u.rays_true_error_worst_px)):
        error = np.linalg.norm(error_against(
            solved.joint.problem, 0, model, true_camera_from_reference=np.eye(4),
            true_reference_from_board=truth, range_m=umap.range_m, pixels=umap.pixels), axis=2)
        assert median == pytest.approx(float(np.nanmedian(error)), rel=1e-6)
        assert worst == pytest.approx(float(np.nanmax(error)), rel=1e-6)
    # the three true errors, the uncertainty and the cross-validation are all of one size
    assert u.aligned_true_error_median_px is not None
    assert u.cross_validation_median_px is not None
    for figure in (u.rays_true_error_median_px, u.aligned_true_error_median_px,
                   u.cross_validation_median_px):
        assert figure is not None and 0.2 < figure / u.rays_median_px < 5.0
