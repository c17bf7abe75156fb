"""The simulator's truth in the solver's terms: the true pose of the board at every instant.

A simulated log carries every target's true pose per image (``{ns}/ground_truth/{target}``:
the target in the camera's optical frame, read by :func:`~.views.detect_views`). The solver
names its board poses by instants (:mod:`.instants`: a held pose is one instant over several
frames) and puts its board frame at the first detected point, which a detector may take from
either end of a symmetric board. Here every instant gets its true ``reference_from_board`` in
the solver's board frame (the reference: the first camera's optical frame), so that a
calibration can be measured the way its projection uncertainty predicts
(:func:`processors.calibration.uncertainty.error_against`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from processors.calibration.board import Board
from processors.calibration.rotation import nearest_rotation, rigid_fit
from replay.geometry import invert
from replay.messages import F64
from replay.records import Scenario, ScenarioCamera, ScenarioTarget

from .instants import ViewsOfRig
from .views import CameraViews

#: a numbering of the board whose true corners land further than this from the detected ones
#: (px, mean) is not the detector's
MATCH_PX = 3.0

__all__ = ["MATCH_PX", "TrueRig", "true_rig"]


@dataclass(frozen=True)
class TrueRig:
    """The true ``camera_from_reference`` ``(4, 4)`` of every camera and the true
    ``reference_from_board`` ``(4, 4)`` of every instant whose frames have a true pose."""

    camera_from_reference: list[F64]
    reference_from_board: dict[int, F64]


def _numberings(target: ScenarioTarget, board: Board) -> list[F64]:
    """Every ``target_from_board`` ``(4, 4)`` that maps the board's points onto the target's:
    as numbered, and for a symmetric board also from the other end."""
    points = target.points_in_target()
    ours = board.points_in_board()
    if points is None or len(points) != len(ours):
        return []
    if target.corner_ids is not None and len(target.corner_ids) == len(points):
        by_id = np.empty_like(points)
        by_id[np.asarray(target.corner_ids)] = points
        points = by_id
    orders = [points, points[::-1]] if board.symmetric else [points]
    fits = [rigid_fit(ours, p) for p in orders]
    return [fit for fit, p in zip(fits, orders, strict=True)
            if np.abs(ours @ fit[:3, :3].T + fit[:3, 3] - p).max() < 1e-3 * board.square_m]


def _mean_pose(poses: list[F64]) -> F64:
    """The mean of nearby poses ``(4, 4)`` (a held board's frames)."""
    out = np.eye(4)
    out[:3, :3] = nearest_rotation(np.sum([p[:3, :3] for p in poses], axis=0))
    out[:3, 3] = np.mean([p[:3, 3] for p in poses], axis=0)
    return out


def true_rig(rig: ViewsOfRig, cameras: list[CameraViews], truth: list[ScenarioCamera | None],
             *, board: Board, scenario: Scenario | None) -> TrueRig | None:
    """The truth of a simulated log in the solver's frames; None without a scenario, a true
    pose of every camera or a target that is the board."""
    if scenario is None or any(t is None for t in truth):
        return None
    cameras_truth = [t for t in truth if t is not None]
    for target in scenario.targets:
        numberings = _numberings(target, board)
        if numberings and any(target.name in c.true_camera_from_target for c in cameras):
            break
    else:
        return None
    world_from_reference = cameras_truth[0].world_from_camera
    reference_from_board: dict[int, F64] = {}
    points = board.points_in_board()
    for view, frames in zip(rig.views, rig.frames_of, strict=True):
        if view.instant in reference_from_board:
            continue
        camera = cameras[view.camera]
        poses = camera.true_camera_from_target.get(target.name, {})
        known = [poses[s] for s in (camera.frames[f].stamp_ns for f in frames) if s in poses]
        if not known:
            continue
        camera_from_target = _mean_pose(known)
        model = cameras_truth[view.camera].model()
        distances = []
        for target_from_board in numberings:
            pose = camera_from_target @ target_from_board
            seen = points[view.point_ids] @ pose[:3, :3].T + pose[:3, 3]
            distances.append(float(np.mean(np.linalg.norm(
                model.project(seen) - view.corners_px, axis=1))))
        best = int(np.argmin(distances))
        if not distances[best] <= MATCH_PX:  # NaN: the board behind the camera
            continue
        reference_from_camera = invert(world_from_reference) \
            @ cameras_truth[view.camera].world_from_camera
        reference_from_board[view.instant] = reference_from_camera @ camera_from_target \
            @ numberings[best]
    return TrueRig([invert(c.world_from_camera) @ world_from_reference for c in cameras_truth],
                   reference_from_board)
