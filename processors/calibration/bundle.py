"""Joint refinement of every camera, the rig and every board pose in one least-squares problem.

The unknowns are the free intrinsics of each camera, ``camera_from_reference`` of every camera
but the first (the reference, camera 0; stereo is N = 2) and ``reference_from_board`` of every
instant the board was seen, and with ``warp`` the board's bow (:mod:`.warp`, two unknowns
shared by every view). A view is one camera's corners at one instant; views of the same
instant share its board pose, which ties the cameras together. The residual of a corner is
``weight * (projected - observed)`` in pixels.

The problem is a bundle adjustment: each corner depends on one board pose and on the few
global unknowns of its camera, so ``J^T J`` is an arrow: a small global block, one 6 x 6
block per board pose and their coupling. Levenberg-Marquardt steps eliminate the pose blocks
(Schur complement, :mod:`.normal`), which costs a few milliseconds for thousands of views,
where a generic sparse least-squares solver (``scipy.optimize.least_squares`` with LSMR) needs
minutes for the same problem and stops short of the optimum. The same blocks give the
covariance. Rotations are updated on the manifold: ``R <- exp([d]x) R``. This module holds the
problem (unknowns, observations, their layout) and its linearization.

A light prior on some intrinsics (:mod:`.prior`) adds one residual per parameter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from replay.messages import F64

from ..errors import ProcessorError
from . import prior, rotation
from .lens import INTRINSIC_NAMES, project
from .warp import warp_shapes, warped

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]
#: views linearized at once by :func:`refine` and for residuals: the Jacobian blocks (about
#: 1 KB per corner) of a few MB are held at a time, not of every view of a long log
CHUNK_VIEWS = 128


@dataclass(frozen=True)
class CameraSetup:
    """What is estimated for one camera: the ``free`` intrinsics (names from
    :data:`~processors.calibration.lens.INTRINSIC_NAMES`); with ``tie_aspect`` fx moves
    with fy at the seed's ratio (camera_calibration's fixed aspect ratio)."""

    distortion_model: str
    size: tuple[int, int]
    free: tuple[str, ...]
    tie_aspect: bool = False

    def __post_init__(self) -> None:
        names = INTRINSIC_NAMES[self.distortion_model]
        unknown = set(self.free) - set(names)
        if unknown:
            raise ProcessorError(f"{self.distortion_model} has no {', '.join(sorted(unknown))}")

    def basis(self, intrinsics: F64) -> tuple[F64, list[str]]:
        """``(K, F)`` map from free parameters to the intrinsic vector, and their names."""
        names = INTRINSIC_NAMES[self.distortion_model]
        columns, labels = [], []
        for name in names:
            if name not in self.free or (self.tie_aspect and name == "fx"):
                continue
            column = np.zeros(len(names))
            column[names.index(name)] = 1.0
            if self.tie_aspect and name == "fy":
                column[names.index("fx")] = intrinsics[0] / intrinsics[1]
            columns.append(column)
            labels.append(name)
        return (np.column_stack(columns) if columns else np.zeros((len(names), 0))), labels


@dataclass
class RigState:
    """Intrinsic vectors per camera; ``camera_from_reference`` rotations ``(N, 3, 3)`` and
    translations ``(N, 3)`` (camera 0 is the reference: identity); ``reference_from_board``
    rotations ``(P, 3, 3)`` and translations ``(P, 3)`` per instant; the board's bow
    ``board_warp_m`` ``(2,)`` (:mod:`.warp`)."""

    intrinsics: list[F64]
    rig_rotation: F64
    rig_translation: F64
    board_rotation: F64
    board_translation: F64
    board_warp_m: F64 = field(default_factory=lambda: np.zeros(2))

    def copy(self) -> RigState:
        """An independent copy (arrays copied)."""
        return RigState([i.copy() for i in self.intrinsics], self.rig_rotation.copy(),
                        self.rig_translation.copy(), self.board_rotation.copy(),
                        self.board_translation.copy(), self.board_warp_m.copy())

    def camera_from_reference(self, camera: int) -> F64:
        """``(4, 4)`` transform of one camera."""
        out = np.eye(4)
        out[:3, :3], out[:3, 3] = self.rig_rotation[camera], self.rig_translation[camera]
        return out

    def reference_from_board(self, instant: int) -> F64:
        """``(4, 4)`` board pose of one instant in the reference camera."""
        out = np.eye(4)
        out[:3, :3] = self.board_rotation[instant]
        out[:3, 3] = self.board_translation[instant]
        return out


@dataclass
class Observations:
    """The corners of every view, one row per view and one column per board point.

    ``observed`` ``(V, N, 2)`` pixels, ``mask`` ``(V, N)`` which of them count (seen and not
    rejected), ``camera`` and ``instant`` ``(V,)``, ``weight`` ``(V,)`` residual scale.
    """

    camera: I64
    instant: I64
    observed: F64
    mask: B8
    weight: F64

    def __post_init__(self) -> None:
        if np.any(np.diff(self.camera) < 0):
            raise ProcessorError("views must be ordered by camera")

    @property
    def view_count(self) -> int:
        """Number of views (rows)."""
        return len(self.camera)

    @property
    def camera_slices(self) -> list[slice]:
        """The views of each camera (0 .. max camera), as slices."""
        return self.slices_of(int(self.camera.max()) + 1 if len(self.camera) else 0)

    def slices_of(self, cameras: int) -> list[slice]:
        """The views of cameras ``0 .. cameras - 1`` (empty for a camera without any)."""
        bounds = np.searchsorted(self.camera, np.arange(cameras + 1))
        return [slice(int(bounds[c]), int(bounds[c + 1])) for c in range(cameras)]

    def rows(self, rows: slice) -> Observations:
        """The views of ``rows`` (views, not copies)."""
        return Observations(self.camera[rows], self.instant[rows], self.observed[rows],
                            self.mask[rows], self.weight[rows])

    def corners(self, cameras: int) -> list[int]:
        """The corners seen by each of ``cameras`` cameras (its views' masks)."""
        seen = np.bincount(self.camera, weights=self.mask.sum(axis=1), minlength=cameras)
        return [int(n) for n in seen]

    def with_mask(self, mask: B8) -> Observations:
        """The same observations with another mask ``(V, N)`` of the corners that count."""
        return Observations(self.camera, self.instant, self.observed, mask, self.weight)


@dataclass
class Layout:
    """Where each unknown sits: the global block (each camera's free intrinsics, then the rig
    rotation and translation of cameras 1..N-1, then the board's warp when estimated), then 6
    per board pose (rotation, then translation, as increments)."""

    setups: list[CameraSetup]
    bases: list[F64]
    names: list[list[str]]
    intrinsic_columns: list[I64]
    rig_columns: list[I64]  # (6,) per camera; empty for the reference
    global_count: int
    prior_px: F64 = field(default_factory=lambda: np.zeros(0))  # (G,) see .prior
    warp_columns: I64 = field(default_factory=lambda: np.zeros(0, np.int64))  # (2,) or none
    corners: tuple[int, ...] = ()  # per camera, the corners its views show (weigh the prior)
    stated_prior_px: F64 = field(default_factory=lambda: np.zeros(0))  # (G,) the covariance's

    def prior_residual(self, state: RigState) -> F64:
        """``(G,)`` the prior's residuals (px): ``prior_px`` times the parameter's value."""
        out = np.zeros(self.global_count)
        for camera, columns in enumerate(self.intrinsic_columns):
            weights = self.prior_px[columns]
            if np.any(weights):
                names = INTRINSIC_NAMES[self.setups[camera].distortion_model]
                values = np.array([state.intrinsics[camera][names.index(n)]
                                   for n in self.names[camera]])
                out[columns] = weights * values
        return out

    @classmethod
    def of(cls, setups: list[CameraSetup], seed: RigState, *, corners: Sequence[int],
           warp: bool = False) -> Layout:
        """The layout of cameras ``setups`` around ``seed`` (its fx / fy ratios), whose views
        show ``corners`` corners per camera (they weigh the prior, :mod:`.prior`); with
        ``warp`` the board's warp is estimated (else held at ``seed``'s)."""
        bases, names, intrinsic_columns, rig_columns = [], [], [], []
        at = 0
        for setup, intrinsics in zip(setups, seed.intrinsics, strict=True):
            basis, labels = setup.basis(intrinsics)
            bases.append(basis)
            names.append(labels)
            intrinsic_columns.append(np.arange(at, at + len(labels)))
            at += len(labels)
        for camera in range(len(setups)):
            rig_columns.append(np.arange(at, at + 6) if camera else np.zeros(0, np.int64))
            at += 6 if camera else 0
        warp_columns = np.arange(at, at + 2) if warp else np.zeros(0, np.int64)
        at += len(warp_columns)
        models = [s.distortion_model for s in setups]
        weights = prior.weights(models, names, intrinsic_columns, at, corners)
        stated = prior.stated_weights(models, names, intrinsic_columns, at, corners)
        return cls(setups, bases, names, intrinsic_columns, rig_columns, at, weights,
                   warp_columns, tuple(corners), stated)

    def global_columns(self, camera: int) -> I64:
        """Columns of one camera's intrinsics, rig transform and the board's warp in the
        global block."""
        return np.concatenate([self.intrinsic_columns[camera], self.rig_columns[camera],
                               self.warp_columns])

    def step(self, state: RigState, d_global: F64, d_pose: F64) -> RigState:
        """``state`` moved by increments of the global unknowns ``(G,)`` and poses ``(P, 6)``."""
        out = state.copy()
        for camera, basis in enumerate(self.bases):
            out.intrinsics[camera] = state.intrinsics[camera] \
                + basis @ d_global[self.intrinsic_columns[camera]]
            if camera:
                d = d_global[self.rig_columns[camera]]
                out.rig_rotation[camera] = rotation.matrices(d[None, :3])[0] \
                    @ state.rig_rotation[camera]
                out.rig_translation[camera] = state.rig_translation[camera] + d[3:]
        out.board_rotation = rotation.matrices(d_pose[:, :3]) @ state.board_rotation
        out.board_translation = state.board_translation + d_pose[:, 3:]
        out.board_warp_m = state.board_warp_m + d_global[self.warp_columns] \
            if len(self.warp_columns) else state.board_warp_m.copy()
        return out


@dataclass
class Linearization:
    """Residuals ``(V, N, 2)`` (zero where masked) and the non-zero Jacobian blocks: per view
    d/d its board pose ``(V, 2N, 6)`` and d/d its camera's global columns ``(V, 2N, G_c)``
    (stored per camera)."""

    residuals: F64
    pose: F64
    global_blocks: list[F64]  # per camera, for its views (a slice of the views)
    prior: F64 = field(default_factory=lambda: np.zeros(0))  # (G,) the prior's residuals

    @property
    def cost(self) -> float:
        """Sum of squared residuals, the prior's included."""
        return float(np.sum(self.residuals ** 2) + np.sum(self.prior ** 2))


def times(a: F64, b: F64) -> F64:
    """``a @ b`` for a tall ``a`` ``(..., K)`` and a small ``b`` ``(K, C)``, element-wise.

    OpenBLAS splits such products over threads, which costs 20x more than the arithmetic
    when the machine is busy; K x C multiply-adds of long vectors do not.
    """
    out = np.zeros((*a.shape[:-1], b.shape[1]))
    for k, c in zip(*np.nonzero(b), strict=True):
        out[..., c] += a[..., k] * b[k, c]
    return out


def cross(a: F64, b: F64) -> F64:
    """Cross products of ``a`` ``(M, 1, 3)`` or ``(M, 3)`` with ``b`` (broadcast), element-wise."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def view_chunks(count: int) -> list[slice]:
    """The views of a problem in slices of :data:`CHUNK_VIEWS`."""
    return [slice(start, min(start + CHUNK_VIEWS, count))
            for start in range(0, count, CHUNK_VIEWS)]


def linearize(state: RigState, layout: Layout, obs: Observations, points_in_board: F64, *,
              jacobian: bool = True) -> Linearization:
    """Residuals and Jacobian blocks of every corner at ``state`` (without ``jacobian``: the
    residuals alone, computed :data:`CHUNK_VIEWS` views at a time)."""
    if jacobian:
        return _linearize(state, layout, obs, points_in_board, jacobian=True)
    v_count, n = obs.mask.shape
    residuals = np.empty((v_count, n, 2))
    for rows in view_chunks(v_count):
        residuals[rows] = _linearize(state, layout, obs.rows(rows), points_in_board,
                                     jacobian=False).residuals
    return residuals_only(residuals, layout, layout.prior_residual(state))


def residuals_only(residuals: F64, layout: Layout, prior_residual: F64) -> Linearization:
    """A linearization holding ``residuals`` ``(V, N, 2)`` without Jacobian blocks."""
    n = residuals.shape[1]
    return Linearization(residuals, np.zeros((0, 2 * n, 6)),
                         [np.zeros((0, 2 * n, 0)) for _ in layout.setups], prior_residual)


def _linearize(state: RigState, layout: Layout, obs: Observations, points_in_board: F64, *,
               jacobian: bool) -> Linearization:
    v_count, n = obs.mask.shape
    rotations = state.board_rotation[obs.instant]  # (V, 3, 3)
    points_in_board = warped(points_in_board, state.board_warp_m)
    shapes = warp_shapes(points_in_board) if len(layout.warp_columns) else np.zeros((n, 0))
    # board points turned into the reference frame (before the translation), (V, N, 3)
    turned = np.stack([rotations[:, i, 0, None] * points_in_board[:, 0]
                       + rotations[:, i, 1, None] * points_in_board[:, 1]
                       + rotations[:, i, 2, None] * points_in_board[:, 2]
                       for i in range(3)], axis=2)
    in_reference = turned + state.board_translation[obs.instant][:, None, :]
    scale = obs.mask * obs.weight[:, None]  # (V, N)
    residuals = np.empty((v_count, n, 2))
    pose = np.empty((v_count, n, 2, 6)) if jacobian else np.zeros((0, n, 2, 6))
    blocks = []
    for camera, (setup, views) in enumerate(zip(layout.setups,
                                                obs.slices_of(len(layout.setups)),
                                                strict=True)):
        count = views.stop - views.start
        width = layout.bases[camera].shape[1] + (6 if camera else 0) + shapes.shape[1]
        if not count or not jacobian:
            blocks.append(np.zeros((count, 2 * n, width if jacobian else 0)))
            if not count:
                continue
        r_c, t_c = state.rig_rotation[camera], state.rig_translation[camera]
        turned_c = times(in_reference[views].reshape(-1, 3), r_c.T)  # rig rotation applied
        uv, d_point, d_intrinsics = project(setup.distortion_model, state.intrinsics[camera],
                                            turned_c + t_c)
        s = scale[views].reshape(-1, 1)
        counted = s[:, 0] != 0
        if not counted.all():  # a board point not seen may not project (NaN): 0 * NaN is NaN
            uv = np.where(counted[:, None], uv, 0.0)
            d_point[~counted], d_intrinsics[~counted] = 0.0, 0.0
        residuals[views] = (s * (uv - obs.observed[views].reshape(-1, 2))).reshape(-1, n, 2)
        if not jacobian:
            continue
        d_point *= s[:, :, None]  # (M, 2, 3)
        # R_p <- exp([d]x) R_p moves a point by -[R_p X]x d, seen through the rig rotation
        e = times(d_point, r_c)
        pose_views = pose[views].reshape(-1, 2, 6)
        pose_views[:, :, :3] = cross(turned[views].reshape(-1, 1, 3), e)
        pose_views[:, :, 3:] = e
        free = layout.bases[camera].shape[1]
        block = np.empty((count * n, 2, width))
        block[:, :, :free] = times(d_intrinsics * s[:, :, None], layout.bases[camera])
        if camera:
            block[:, :, free:free + 3] = cross(turned_c.reshape(-1, 1, 3), d_point)
            block[:, :, free + 3:free + 6] = d_point
        if shapes.shape[1]:
            # the warp moves a point along its board's z axis, R_p e_z, in the reference
            along_z = np.einsum("vnik,vk->vni", e.reshape(count, n, 2, 3),
                                rotations[views, :, 2])
            block[:, :, width - 2:] = (along_z[..., None] * shapes[None, :, None, :]
                                       ).reshape(-1, 2, 2)
        blocks.append(block.reshape(count, 2 * n, -1))
    return Linearization(residuals, pose.reshape(len(pose), 2 * n, 6), blocks,
                         layout.prior_residual(state))
