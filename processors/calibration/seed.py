"""Starting points for the joint refinement: OpenCV's calibration, board poses, rig transforms.

OpenCV's solvers (``calibrateCamera``, ``fisheye.calibrate``, ``solvePnP``) give a solution
close enough for Levenberg-Marquardt to converge from; the joint refinement then uses every
view. OpenCV's calibration is dense in the views, so it sees an evenly spaced sample of them.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import cv2
import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.lens_models import lens_model
from replay.messages import F64

from ..errors import ProcessorError
from . import bundle, rotation
from .lens import intrinsics_of
from .opencv_lens import opencv_lens
from .options import CalibrationOptions

I64 = npt.NDArray[np.int64]
#: views OpenCV's solver sees when seeding a camera
SEED_VIEWS = 40
#: the cross-validations (the lens order, the board's warp, the halves) measure an even
#: sample of at most this many views or board poses: a waved board's neighbouring frames are
#: nearly one view, and past a few hundred views the choices and figures settle while their
#: cost grows with the views (held boards give far fewer)
STATISTICS_VIEWS = 240
#: rig transforms of two views agree when their rotations differ by less than this
RIG_AGREEMENT_RAD = math.radians(2.0)
#: a seed view whose RMS error exceeds max(factor x the median, floor) is left out of the seed
SEED_OUTLIER_FACTOR = 5.0
SEED_OUTLIER_FLOOR_PX = 0.5


def spread(count: int, most: int) -> list[int]:
    """Up to ``most`` indices evenly spread over ``range(count)``."""
    if count <= most:
        return list(range(count))
    return sorted({round(i * (count - 1) / (most - 1)) for i in range(most)})


def seed_model(points: list[F64], corners: list[F64], size: tuple[int, int],
               options: CalibrationOptions) -> CameraModel:
    """A camera from OpenCV's calibration of views ``corners[i]`` ``(M_i, 2)`` of the board
    points ``points[i]`` ``(M_i, 3)`` (an even sample of at most :data:`SEED_VIEWS`).

    A view that is not the board (a wrong detection) can pull OpenCV's solution far enough
    for the refinement to start in the wrong place: views far above the rest are left out
    and the seed solved again, twice at most.
    """
    pick = spread(len(corners), SEED_VIEWS)
    pick, model = _without_stopping_views(points, corners, pick, size, options)
    for _round in range(2):
        errors = np.array([view_rms_px(points[i], corners[i], model) for i in pick])
        limit = max(SEED_OUTLIER_FACTOR * float(np.nanmedian(errors)), SEED_OUTLIER_FLOOR_PX)
        keep = [i for i, e in zip(pick, errors, strict=True) if e <= limit]
        if len(keep) == len(pick) or len(keep) < max(5, len(pick) // 2):
            break
        try:
            pick, model = _without_stopping_views(points, corners, keep, size, options)
        except ProcessorError:
            break  # the views without the far ones do not solve: keep the solution with them
    return model


def _without_stopping_views(points: list[F64], corners: list[F64], pick: list[int],
                            size: tuple[int, int], options: CalibrationOptions
                            ) -> tuple[list[int], CameraModel]:
    """OpenCV's calibration of the views ``pick``; when it stops on one view (a degenerate
    pose on the way, which OpenCV asserts against), that view, found by solving without one
    view at a time, is left out."""
    try:
        return pick, opencv_calibration([points[i] for i in pick],
                                         [corners[i] for i in pick], size, options)
    except ProcessorError as err:
        failure = err
    for i in pick:
        rest = [j for j in pick if j != i]
        try:
            return rest, opencv_calibration([points[j] for j in rest],
                                             [corners[j] for j in rest], size, options)
        except ProcessorError:
            continue
    raise failure


def view_rms_px(points: F64, corners: F64, model: CameraModel) -> float:
    """RMS reprojection error of one view with its pose fitted (inf when PnP fails)."""
    pose = board_pose(points, corners, model)
    if pose is None:
        return float("inf")
    projected = model.project(points @ pose[:3, :3].T + pose[:3, 3])
    return float(np.sqrt(np.mean(np.sum((projected - corners) ** 2, axis=1))))


_SERIAL = threading.Lock()
_serial_users = [0, 0]  # calls inside, OpenCV's thread count before the first


@contextmanager
def one_opencv_thread() -> Iterator[None]:
    """OpenCV on one thread while inside: its calibration solvers sum in parallel, in an order
    that changes from run to run, and the last bits they change moved a noise-free solve's
    final coefficients by up to 0.3 % (a calibration gives the same result twice). Nested
    and concurrent users share one setting; the last one out restores OpenCV's count."""
    with _SERIAL:
        if _serial_users[0] == 0:
            _serial_users[1] = cv2.getNumThreads()
            cv2.setNumThreads(1)
        _serial_users[0] += 1
    try:
        yield
    finally:
        with _SERIAL:
            _serial_users[0] -= 1
            if _serial_users[0] == 0:
                cv2.setNumThreads(_serial_users[1])


def opencv_calibration(points: list[F64], corners: list[F64], size: tuple[int, int],
                       options: CalibrationOptions) -> CameraModel:
    """OpenCV's calibration of every view given, on one thread (ProcessorError when it
    stops)."""
    model = options.distortion_model
    try:
        with one_opencv_thread():
            k, d = opencv_lens(model).calibrate(points, corners, size, options)
    except cv2.error as err:
        raise ProcessorError(f"calibration failed: {str(err).strip().splitlines()[-1]}") from None
    coefficients = len(lens_model(model).coefficients)
    return CameraModel(size[0], size[1], k, model, d.reshape(-1)[:coefficients])


def board_pose(points: F64, corners: F64, model: CameraModel) -> F64 | None:
    """``camera_from_board`` (4, 4) of one view by PnP on the undistorted corners; None when
    it fails."""
    normalized = model.undistort_pixels(corners)
    keep = np.isfinite(normalized).all(axis=1)
    if keep.sum() < 4:
        return None
    try:
        ok, rvec, tvec = cv2.solvePnP(points[keep].astype(np.float64),
                                      normalized[keep].astype(np.float64), np.eye(3), None,
                                      flags=cv2.SOLVEPNP_IPPE)
    except cv2.error:  # degenerate corners (all on one line): no pose
        return None
    if not ok:
        return None
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(rvec)[0]
    pose[:3, 3] = np.asarray(tvec).reshape(3)
    return pose


def rig_transform(camera_from_board: list[F64], reference_from_board: list[F64]) -> F64:
    """``camera_from_reference`` (4, 4) most views agree on, from pairs of board poses seen by
    both cameras at the same instants: rotations within :data:`RIG_AGREEMENT_RAD` of the
    best-supported one are averaged, translations by their median."""
    if not camera_from_board:
        raise ProcessorError("a camera never sees the board at the same time as the first one")
    candidates = np.stack([c @ np.linalg.inv(r) for c, r in zip(camera_from_board,
                                                                 reference_from_board,
                                                                 strict=True)])
    rvecs = rotation.rotation_vectors(candidates[:, :3, :3])
    best = int(np.argmax(rotation.support(candidates[:, :3, :3], RIG_AGREEMENT_RAD)))
    agree = rotation.within(candidates[:, :3, :3], candidates[best, :3, :3], RIG_AGREEMENT_RAD)
    mean = rotation.nearest_rotation(candidates[agree, :3, :3].sum(axis=0))
    out = np.eye(4)
    out[:3, :3] = mean if np.all(np.isfinite(mean)) else rotation.matrices(rvecs[best:best + 1])[0]
    out[:3, 3] = np.median(candidates[agree, :3, 3], axis=0)
    return out


def seed_state(points_in_board: F64, obs: bundle.Observations, models: list[CameraModel],
               instant_count: int, *, min_points: int) -> bundle.RigState:
    """The solve's start: board poses by PnP through ``models`` (views with at least
    ``min_points`` corners); each instant from the lowest-numbered camera that saw it; rig
    transforms by consensus over the instants a camera shares with the reference, or with a
    camera already placed (:func:`chained_rig`)."""
    poses: dict[tuple[int, int], F64] = {}
    for row in range(obs.view_count):
        ids = np.flatnonzero(obs.mask[row])
        if len(ids) < min_points:
            continue
        pose = board_pose(points_in_board[ids], obs.observed[row, ids],
                          models[int(obs.camera[row])])
        if pose is not None:
            poses[(int(obs.camera[row]), int(obs.instant[row]))] = pose
    cameras = len(models)
    rig = chained_rig(poses, cameras)
    board = np.tile(np.eye(4), (instant_count, 1, 1))
    for instant in range(instant_count):
        for camera in range(cameras):
            if (camera, instant) in poses:
                board[instant] = np.linalg.inv(rig[camera]) @ poses[(camera, instant)]
                break
    return bundle.RigState([intrinsics_of(m) for m in models],
                           np.stack([r[:3, :3] for r in rig]), np.stack([r[:3, 3] for r in rig]),
                           board[:, :3, :3].copy(), board[:, :3, 3].copy())


def chained_rig(poses: dict[tuple[int, int], F64], cameras: int) -> list[F64]:
    """Every camera's ``camera_from_reference`` ``(4, 4)`` from the board poses ``(camera,
    instant) -> camera_from_board``: by consensus over the instants it shares with camera 0,
    or else with the placed camera it shares most instants with (a chain of cameras)."""
    rig: list[F64 | None] = [np.eye(4)] + [None] * (cameras - 1)

    def shared(camera: int, other: int) -> list[int]:
        return [i for (c, i) in poses if c == camera and (other, i) in poses]

    while unplaced := [c for c in range(cameras) if rig[c] is None]:
        direct = [c for c in unplaced if shared(c, 0)]
        links = [(0, c, 0) for c in direct[:1]] or sorted(
            (-len(shared(c, p)), c, p) for c in unplaced for p in range(cameras)
             if rig[p] is not None and shared(c, p))
        if not links:
            raise ProcessorError("a camera never sees the board at the same time as the "
                                 "first one, directly or through another camera")
        _count, camera, placed = links[0]
        instants = shared(camera, placed)
        camera_from_placed = rig_transform([poses[(camera, i)] for i in instants],
                                           [poses[(placed, i)] for i in instants])
        placed_from_reference = rig[placed]
        rig[camera] = camera_from_placed if placed_from_reference is None or placed == 0 \
            else camera_from_placed @ placed_from_reference
    return [r for r in rig if r is not None]
