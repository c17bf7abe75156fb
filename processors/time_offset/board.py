"""The offset between two cameras' stamps from a moving board both of them see.

Each camera's board pose in each of its frames (PnP through its calibration) places the
board's points in that camera over time, a smooth path that a cubic through 4 consecutive
frames follows within noise (:mod:`.interpolation`). Were the stamps right, the second
camera's view of the board at its stamp ``s`` would be the first camera's board at ``s``
seen through the rig; when the second camera stamps ``offset`` late, it is the first
camera's board at ``s - offset``. The offset and the rig (``second_from_first``, solved
with it or given) are fitted to the corners both ways (the second camera's detections
against the first camera's interpolated board, and the first's against the second's),
sub-frame by the interpolation, after a coarse search over ``±search_s`` on the board
points' 3-D agreement.

Only frames where the board moves carry the offset. A held board carries none, nor does a
board that jumps from one held pose to the next between two frames (no polynomial follows
a jump: a frame whose motion is not smooth, its acceleration as large as its speed, is left
out of the interpolation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from ..calibration.lens import intrinsics_of, project
from ..calibration.rotation import matrices, nearest_rotation
from ..calibration.seed import board_pose
from .estimate import (
    CLUSTER_FRAMES,
    MAD_TO_SIGMA,
    NotObservableError,
    OffsetEstimate,
    robust_fit,
)
from .interpolation import Stencils

__all__ = ["BoardTrack", "estimate_board_offset"]

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]

#: samples of a stencil: a cubic through 4 frames around the query time
STENCIL = 4
#: a frame's motion is smooth when its acceleration (second difference of the board's
#: points) is below this share of its speed (first difference), or at the noise's level
SMOOTH_SHARE = 0.5
NOISE_MULTIPLE = 3.0
#: a frame carries the offset when its corners move at least this fast (px per second):
#: a pixel per frame at 30 Hz
MOVING_PX_S = 30.0
#: fewer frames than this carrying it: not observable
MIN_MOVING_FRAMES = 10
#: a standard deviation above this (s) is no measurement
MAX_STD_S = 0.005
#: the cameras agree on the board when the fit's residuals (robust sigma) are within this
#: factor of each camera's own, plus a floor (px), with at least this share of inliers
AGREEMENT_FACTOR = 3.0
AGREEMENT_FLOOR_PX = 0.1
MIN_INLIER_SHARE = 0.7
#: the coarse search's step (s)
SEARCH_STEP_S = 0.005
#: Gauss-Newton has converged when no step is larger: offset (s), rotation (rad),
#: translation (m)
STEPS = np.array([1e-8, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9, 1e-9])


@dataclass(frozen=True)
class BoardTrack:
    """One camera's view of a board over time: the stamps ``stamps_ns`` ``(N,)`` of its
    frames with a board found, each frame's board points ``point_ids`` ``(M_i,)`` and
    their corners ``corners_px`` ``(M_i, 2)``, and the camera's ``model``."""

    stamps_ns: I64
    point_ids: list[I64]
    corners_px: list[F64]
    model: CameraModel


@dataclass(frozen=True)
class _Posed:
    """A track with its board posed: times ``(N,)`` (s from a common origin), the board's
    points in the camera ``(N, P, 3)``, every corner ``(N, P, 2)`` and which are seen
    ``(N, P)``, and the stencils over the frames whose motion is smooth."""

    times_s: F64
    points: F64
    observed: F64
    seen: B8
    stencils: Stencils
    model: CameraModel
    noise_px: float  # robust sigma per coordinate of the frames' own PnP residuals


def _oriented_pose(points_in_board: F64, ids: I64, corners_px: F64, model: CameraModel, *,
                   half_turn: bool) -> tuple[F64, I64, F64] | None:
    """A frame's ``camera_from_board`` by PnP, and its point ids and corners; a board that
    looks the same turned by half a turn is numbered from the end that puts its x axis
    towards the image's right (both cameras of a rig see it so, but for boards seen with
    their x axis near vertical, whose frames the fit leaves out as outliers)."""
    pose = board_pose(points_in_board[ids], corners_px, model)
    if pose is None or not half_turn or pose[0, 0] >= 0:
        return None if pose is None else (pose, ids, corners_px)
    turned_ids = len(points_in_board) - 1 - ids[::-1]
    turned_corners = np.ascontiguousarray(corners_px[::-1])
    pose = board_pose(points_in_board[turned_ids], turned_corners, model)
    return None if pose is None else (pose, turned_ids, turned_corners)


def _posed(track: BoardTrack, points_in_board: F64, origin_ns: int, *,
           half_turn: bool) -> _Posed | None:
    order = np.argsort(track.stamps_ns, kind="stable")
    times: list[int] = []
    points, observed, seen, residuals = [], [], [], []
    for i in order.tolist():
        posed = _oriented_pose(points_in_board, np.asarray(track.point_ids[i], np.int64),
                               np.asarray(track.corners_px[i], np.float64), track.model,
                               half_turn=half_turn)
        if posed is None or (times and track.stamps_ns[i] == times[-1]):
            continue
        pose, ids, corners_px = posed
        times.append(int(track.stamps_ns[i]))
        points.append(points_in_board @ pose[:3, :3].T + pose[:3, 3])
        residuals.append((track.model.project(points[-1][ids]) - corners_px).reshape(-1))
        corners = np.full((len(points_in_board), 2), np.nan)
        corners[ids] = corners_px
        observed.append(corners)
        mask = np.zeros(len(points_in_board), bool)
        mask[ids] = True
        seen.append(mask)
    if len(times) < STENCIL:
        return None
    stacked = np.stack(points)
    times_s = np.asarray((np.asarray(times, dtype=np.int64) - origin_ns) * 1e-9,
                         dtype=np.float64)
    noise = MAD_TO_SIGMA * float(np.median(np.abs(np.concatenate(residuals))))
    return _Posed(times_s, stacked, np.stack(observed), np.stack(seen),
                  Stencils(times_s, STENCIL, _smooth(stacked, track.model, noise)),
                  track.model, noise)


def _smooth(points: F64, model: CameraModel, noise_px: float) -> B8:
    """``(N,)`` frames whose motion a polynomial follows, judged in the image (the board's
    points ``(N, P, 3)`` seen through ``model``): acceleration (second difference, px)
    below :data:`SMOOTH_SHARE` of the speed (half the central difference), or within
    :data:`NOISE_MULTIPLE` times what the corners' noise ``noise_px`` gives a still board
    (the first and last frame: judged by their neighbour)."""
    pixels = model.project(points.reshape(-1, 3)).reshape(*points.shape[:2], 2)
    speed = np.linalg.norm(pixels[2:] - pixels[:-2], axis=2).mean(axis=1) / 2
    acceleration = np.linalg.norm(pixels[2:] - 2 * pixels[1:-1] + pixels[:-2],
                                  axis=2).mean(axis=1)
    # a second difference of three samples each off by noise_px per coordinate
    floor = NOISE_MULTIPLE * noise_px * math.sqrt(6.0 * 2.0)
    inner = (acceleration <= SMOOTH_SHARE * speed) | (acceleration <= floor)
    return np.concatenate([inner[:1], inner, inner[-1:]])


def _interpolated(posed: _Posed, t_s: F64, start: I64) -> tuple[F64, F64]:
    """The board's points ``(Q, P, 3)`` at ``t_s`` from the stencils at ``start``, and
    their velocities ``(Q, P, 3)`` (m/s)."""
    weights, derivative = posed.stencils.weights(t_s, start)
    samples = posed.points[start[:, None] + np.arange(STENCIL)[None, :]]
    return (np.asarray(np.einsum("qk,qkpd->qpd", weights, samples)),
            np.asarray(np.einsum("qk,qkpd->qpd", derivative, samples)))


def _project(model: CameraModel, points: F64) -> tuple[F64, F64]:
    """Pixels ``(M, 2)`` of points ``(M, 3)`` and d pixel / d point ``(M, 2, 3)``."""
    uv, d_point, _ = project(model.distortion_model, intrinsics_of(model), points)
    return uv, d_point


def _skew(v: F64) -> F64:
    """``[v]x`` ``(M, 3, 3)`` of vectors ``(M, 3)``."""
    out = np.zeros((len(v), 3, 3))
    out[:, 0, 1], out[:, 0, 2], out[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    out[:, 1, 0], out[:, 2, 0], out[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    return out


def _kabsch(source: F64, target: F64) -> F64:
    """``target_from_source`` (4, 4) that best maps points ``(M, 3)`` onto each other."""
    mean_s, mean_t = source.mean(axis=0), target.mean(axis=0)
    rotation = nearest_rotation((target - mean_t).T @ (source - mean_s))
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = mean_t - rotation @ mean_s
    return out


def _agreement(first: _Posed, second: _Posed, offset: float,
               second_from_first: F64 | None) -> tuple[float, int, F64]:
    """How well (mean squared distance, m^2) the second camera's posed board agrees with
    the first's interpolated at ``offset`` through the best rig (or the one given), over how
    many frames, and that rig."""
    start, found = first.stencils.locate(second.times_s - offset)
    if found.sum() < MIN_MOVING_FRAMES:
        return math.inf, int(found.sum()), np.eye(4)
    source, _ = _interpolated(first, (second.times_s - offset)[found], start[found])
    target = second.points[found]
    rig = _kabsch(source.reshape(-1, 3), target.reshape(-1, 3)) \
        if second_from_first is None else second_from_first
    moved = source @ rig[:3, :3].T + rig[:3, 3]
    return float(np.mean(np.sum((moved - target) ** 2, axis=2))), int(found.sum()), rig


def _coarse(first: _Posed, second: _Posed, search_s: float,
            second_from_first: F64 | None) -> tuple[float, F64]:
    """The offset on a grid over ``±search_s`` (:data:`SEARCH_STEP_S`, then a tenth of it
    around the best) whose 3-D agreement (:func:`_agreement`) is best over at least a
    quarter of the most frames any offset pairs, and its rig."""
    grid = np.arange(-search_s, search_s + SEARCH_STEP_S / 2, SEARCH_STEP_S)
    scored = [_agreement(first, second, float(o), second_from_first) for o in grid]
    most = max(count for _, count, _ in scored)
    if most < MIN_MOVING_FRAMES:
        overlap = min(first.times_s[-1], second.times_s[-1] + search_s) \
            - max(first.times_s[0], second.times_s[0] - search_s)
        if overlap <= 0:
            raise NotObservableError("the two cameras never see the board at the same time "
                                     f"(within {search_s * 1000:g} ms)")
        raise NotObservableError(
            "the board is not seen moving in consecutive frames of both cameras (a held "
            "board, repeated frames, or snapshots): a waved board shows the offset, a held "
            "one does not")
    costs = np.array([cost if count >= most / 4 else math.inf for cost, count, _ in scored])
    centre = float(grid[int(np.argmin(costs))])
    fine = centre + np.arange(-10, 11) * SEARCH_STEP_S / 10
    best = min(((*_agreement(first, second, float(o), second_from_first), float(o))
                for o in fine), key=lambda scored: scored[0])
    return best[3], best[2]


@dataclass(frozen=True)
class _BoardFit:
    """What the fit moves: the offset (s) and the rig ``second_from_first`` (4, 4)."""

    offset_s: float
    rig: F64


def _advance(state: _BoardFit, step: F64) -> _BoardFit:
    """``state`` moved by an increment: offset, then (unless held) the rig's rotation
    ``R <- exp([d]x) R`` and translation."""
    if len(step) == 1:
        return _BoardFit(state.offset_s + float(step[0]), state.rig)
    rig = np.eye(4)
    rig[:3, :3] = matrices(step[None, 1:4])[0] @ state.rig[:3, :3]
    rig[:3, 3] = state.rig[:3, 3] + step[4:7]
    return _BoardFit(state.offset_s + float(step[0]), rig)


@dataclass(frozen=True)
class _Direction:
    """One direction of the fit: the frames of ``seen_by`` (rows) predicted from the board
    of ``moved`` interpolated at their times (``sign`` +1: the second camera's frames, at
    ``t - offset`` in the first camera's clock; -1: the first's, at ``t + offset``)."""

    moved: _Posed
    seen_by: _Posed
    rows: I64
    start: I64
    sign: float

    def linearize(self, state: _BoardFit, rig_free: bool) -> tuple[F64, F64]:
        """Residuals ``(2M,)`` of the seen corners and their Jacobian ``(2M, U)``."""
        times = self.seen_by.times_s[self.rows] - self.sign * state.offset_s
        points, velocity = _interpolated(self.moved, times, self.start)
        seen = self.seen_by.seen[self.rows]
        rotation, translation = state.rig[:3, :3], state.rig[:3, 3]
        if self.sign > 0:  # first -> second: X = R P + t
            x = points @ rotation.T + translation
            d_offset = -(velocity @ rotation.T)
        else:  # second -> first: X = R^T (P - t)
            x = (points - translation) @ rotation
            d_offset = velocity @ rotation
        x, d_offset = x[seen], d_offset[seen]
        uv, d_point = _project(self.seen_by.model, x)
        residual = (uv - self.seen_by.observed[self.rows][seen]).reshape(-1)
        columns = [np.einsum("mij,mj->mi", d_point, d_offset)[:, :, None]]
        if rig_free:
            if self.sign > 0:  # d(exp([w]x) R P)/dw = -[R P]x, dX/dt = I
                d_rotation = -_skew(x - translation)
                d_translation = np.broadcast_to(np.eye(3), (len(x), 3, 3))
            else:  # d(R^T exp(-[w]x)(P - t))/dw = R^T [P - t]x, dX/dt = -R^T
                d_rotation = rotation.T @ _skew(x @ rotation.T)
                d_translation = np.broadcast_to(-rotation.T, (len(x), 3, 3))
            columns += [d_point @ d_rotation, d_point @ d_translation]
        return residual, np.concatenate(columns, axis=2).reshape(len(residual), -1)


def estimate_board_offset(first: BoardTrack, second: BoardTrack, *, points_in_board: F64,
                          half_turn: bool = False, search_s: float = 0.25,
                          second_from_first: F64 | None = None) -> OffsetEstimate:
    """How much later ``second`` stamps an instant than ``first``, from the board both see
    (see the module's text), searched within ``±search_s``; ``half_turn``: the board looks
    the same turned by half a turn (a chessboard), so that a detector may number it from
    either end; ``second_from_first`` ``(4, 4)`` holds the rig (None: solved with the
    offset). Raises :class:`NotObservableError` when the board does not move in the frames both
    see, or they never see it at the same time."""
    stamps = [t.stamps_ns for t in (first, second) if len(t.stamps_ns)]
    origin = min(int(np.min(s)) for s in stamps) if stamps else 0
    a, b = (_posed(t, points_in_board, origin, half_turn=half_turn) for t in (first, second))
    if a is None or b is None:
        raise NotObservableError("the board is posed in fewer than 4 frames of a camera")
    offset0, rig0 = _coarse(a, b, search_s, second_from_first)
    # the frames and their stencils, fixed around the coarse offset: the residuals stay
    # smooth in the unknowns while Gauss-Newton moves them
    sides = []
    for moved, seen_by, sign in ((a, b, 1.0), (b, a, -1.0)):
        start, found = moved.stencils.locate(seen_by.times_s - sign * offset0)
        rows = np.flatnonzero(found)
        sides.append(_Direction(moved, seen_by, rows, start[rows], sign))
    period = a.stencils.period_s
    clusters = np.concatenate([
        np.repeat(np.floor(side.seen_by.times_s[side.rows] / (CLUSTER_FRAMES * period)),
                  2 * side.seen_by.seen[side.rows].sum(axis=1)) for side in sides])
    rig_free = second_from_first is None

    def linearize(state: _BoardFit) -> tuple[F64, F64]:
        parts = [side.linearize(state, rig_free) for side in sides]
        return (np.concatenate([r for r, _ in parts]),
                np.concatenate([j for _, j in parts], axis=0))

    tolerance = STEPS if rig_free else STEPS[:1]
    fit = robust_fit(linearize, _advance, _BoardFit(offset0, rig0),
                     clusters=clusters.astype(np.int64), tolerance=tolerance)
    state = fit.state
    moving = sum(_moving(side, state) for side in sides)
    std = math.sqrt(max(float(fit.covariance[0, 0]), 0.0))
    frames = sum(len(side.rows) for side in sides)
    alone_px = max(a.noise_px, b.noise_px)
    if not fit.sigma <= AGREEMENT_FACTOR * alone_px + AGREEMENT_FLOOR_PX \
            or fit.inliers.mean() < MIN_INLIER_SHARE:
        raise NotObservableError(
            f"the cameras' views of the board do not agree at any offset within "
            f"±{search_s * 1000:g} ms ({fit.sigma:.2f} px apart where each camera alone fits "
            f"it to {alone_px:.2f} px): a larger offset, or views of different boards")
    if moving < MIN_MOVING_FRAMES or not std <= MAX_STD_S:
        raise NotObservableError(
            f"the board hardly moves in the frames both cameras see ({moving} of {frames} "
            f"frames move it {MOVING_PX_S:g} px/s or more; a waved board shows the offset, a "
            "held one does not)")
    used = fit.residuals[fit.inliers]
    return OffsetEstimate(state.offset_s, std, moving, frames,
                          math.sqrt(2.0 * float(np.mean(used ** 2))), "board", state.rig)


def _moving(side: _Direction, state: _BoardFit) -> int:
    """Frames of one side whose board moves at least :data:`MOVING_PX_S` in the image."""
    times = side.seen_by.times_s[side.rows] - side.sign * state.offset_s
    points, velocity = _interpolated(side.moved, times, side.start)
    rotation, translation = state.rig[:3, :3], state.rig[:3, 3]
    if side.sign > 0:
        x, v = points @ rotation.T + translation, velocity @ rotation.T
    else:
        x, v = (points - translation) @ rotation, velocity @ rotation
    _, d_point = _project(side.seen_by.model, x.reshape(-1, 3))
    speed = np.linalg.norm(np.einsum("mij,mj->mi", d_point, v.reshape(-1, 3)), axis=1)
    return int((speed.reshape(len(times), -1).mean(axis=1) >= MOVING_PX_S).sum())
