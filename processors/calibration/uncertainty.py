"""Projection uncertainty over the image, as mrcal computes it, and the error it predicts.

A calibration is used to project points. For a pixel ``q`` of camera ``c``, take the point
at the working range ``r`` on its ray, express it in every board frame through the solved
poses, and map it back through the *perturbed* poses, rig and intrinsics, averaging over
the board poses (mrcal's "mean frames"): the camera frame is only known relative to the
boards, and a rotation the intrinsics cannot tell from a turn of every pose costs nothing.
Linearised, the reprojected pixel moves by ``G d`` for a parameter error ``d``; with the
parameter covariance ``sigma^2 (J^T J)^-1`` (board poses included, eliminated through the
Schur complement) its covariance is ``sigma^2 G (J^T J)^-1 G^T`` (2 x 2 per pixel). The map
reports the standard deviation in the worst direction.

:func:`error_against` evaluates the same reprojection with the simulator's true model and
board poses, so the true error and the predicted uncertainty measure the same thing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from .bundle import cross, times
from .joint import Problem
from .lens import model_of, project
from .normal import NormalEquations

#: pixels per grid cell of the uncertainty map
GRID_STEP_PX = 16


class OverImage:
    """A figure in pixels at every grid pixel of an image (:attr:`values_px`, NaN where it
    has none), summarised by its worst and median values."""

    @property
    def values_px(self) -> F64:
        """The figure ``(rows, cols)`` at the grid pixels."""
        raise NotImplementedError

    @property
    def worst_px(self) -> float:
        """Largest value over the image (px)."""
        return float(np.nanmax(self.values_px))

    @property
    def median_px(self) -> float:
        """Median value over the image (px)."""
        return float(np.nanmedian(self.values_px))


@dataclass(frozen=True)
class UncertaintyMap(OverImage):
    """Projection uncertainty of one camera: ``sigma_px`` ``(rows, cols)`` is the standard
    deviation in the worst direction at the grid pixels ``pixels`` ``(rows, cols, 2)``;
    ``covariance`` ``(rows, cols, 2, 2)``."""

    camera: int
    range_m: float
    pixels: F64
    covariance: F64
    sigma_px: F64

    @property
    def values_px(self) -> F64:
        """The uncertainty ``sigma_px``."""
        return self.sigma_px


def grid(size: tuple[int, int], step_px: int = GRID_STEP_PX) -> F64:
    """Pixel centres ``(rows, cols, 2)`` every ``step_px`` across the image, both edges
    included."""
    width, height = size
    us = np.linspace(0.0, width - 1.0, max(2, round((width - 1) / step_px) + 1))
    vs = np.linspace(0.0, height - 1.0, max(2, round((height - 1) / step_px) + 1))
    u, v = np.meshgrid(us, vs)
    return np.stack([u, v], axis=2)


def working_range_m(problem: Problem) -> float:
    """Median distance of the board poses from the reference camera (m)."""
    seen = problem.normal.seen
    centre = problem.points_in_board.mean(axis=0)
    distances = np.linalg.norm(problem.state.board_rotation[seen] @ centre
                               + problem.state.board_translation[seen], axis=1)
    return float(np.median(distances))


def _points_in_reference(problem: Problem, camera: int, pixels: F64, range_m: float
                         ) -> tuple[F64, F64, F64]:
    """Points ``(M, 3)`` at ``range_m`` on the rays of ``pixels`` ``(M, 2)``, in camera
    ``camera`` and in the reference frame, and the rig rotation of the camera."""
    state, setup = problem.state, problem.layout.setups[camera]
    model = model_of(setup.distortion_model, state.intrinsics[camera], setup.size)
    in_camera = model.pixel_rays(pixels) * range_m
    r_c, t_c = state.rig_rotation[camera], state.rig_translation[camera]
    return in_camera, times(in_camera - t_c, r_c), r_c


def projection_uncertainty(problem: Problem, camera: int, *, range_m: float | None = None,
                           step_px: int = GRID_STEP_PX) -> UncertaintyMap:
    """The projection uncertainty map of one camera at ``range_m`` (default: the working
    range, :func:`working_range_m`).

    A grid pixel's reprojection moves by ``g_global`` per global unknown and, per seen board
    pose ``p``, by ``[lever_p x e; e]`` per pose unknown, where ``lever_p = X - t_p`` (the
    point in the reference frame less the pose's translation). That is linear in
    ``a_p = (1, t_p)``: ``g_p = sum_j a_pj H_j`` with four ``(6, 2)`` blocks ``H_j`` per pixel.
    With the pose blocks eliminated (Schur complement ``S``, pose inverses ``B_p^-1``, coupling
    ``C_p B_p^-1``), ``g^T (J^T J)^-1 g = r^T S^-1 r + sum_p g_p^T B_p^-1 g_p`` and
    ``r = g_global - sum_p C_p B_p^-1 g_p``; both sums over the poses reduce to moments of
    ``a_p`` taken once per camera, so a waved board's thousand poses cost no more per pixel
    than ten."""
    range_m = working_range_m(problem) if range_m is None else range_m
    size = problem.layout.setups[camera].size
    pixels = grid(size, step_px)
    flat = pixels.reshape(-1, 2)
    covariance = np.full((len(flat), 2, 2), np.nan)
    state, layout, normal = problem.state, problem.layout, problem.stated_normal
    setup = layout.setups[camera]
    seen = np.flatnonzero(normal.seen)
    in_camera, in_reference, r_c = _points_in_reference(problem, camera, flat, range_m)
    valid = np.flatnonzero(np.isfinite(in_camera).all(axis=1))
    if len(valid) and len(seen):
        in_camera, in_reference = in_camera[valid], in_reference[valid]
        _uv, d_point, d_intrinsics = project(setup.distortion_model, state.intrinsics[camera],
                                             in_camera)
        m = len(in_camera)
        g_global = np.zeros((layout.global_count, m, 2))
        g_global[layout.intrinsic_columns[camera]] = np.transpose(
            times(d_intrinsics, layout.bases[camera]), (2, 0, 1))
        if camera:
            rig = np.concatenate([cross(times(in_reference, r_c.T)[:, None, :], d_point),
                                  d_point], axis=2)
            g_global[layout.rig_columns[camera]] = np.transpose(rig, (2, 0, 1))
        # each seen board pose moves the mean point by 1/P of its own displacement
        e = times(d_point, r_c) / len(seen)  # (m, 2, 3)
        h = np.zeros((4, 6, m, 2))
        h[0, :3] = np.transpose(cross(in_reference[:, None, :], e), (2, 0, 1))
        h[0, 3:] = np.transpose(e, (2, 0, 1))
        for axis in range(3):  # minus t_p's axis: the lever's part from the pose
            unit = np.zeros(3)
            unit[axis] = -1.0
            h[1 + axis, :3] = np.transpose(cross(unit, e), (2, 0, 1))
        flat_h = h.reshape(24, 2 * m)
        reduce, quadratic, schur = _pose_moments(normal, state.board_translation, seen)
        r = g_global.reshape(layout.global_count, 2 * m) - reduce @ flat_h
        x = np.linalg.solve(schur, r) if len(schur) else r
        blocks = np.einsum("gmk,gml->mkl", r.reshape(-1, m, 2), x.reshape(-1, m, 2)) \
            + np.einsum("imk,iml->mkl", h.reshape(24, m, 2),
                        (quadratic @ flat_h).reshape(24, m, 2))
        covariance[valid] = problem.sigma_px ** 2 * blocks
    covariance = covariance.reshape(*pixels.shape[:2], 2, 2)
    sigma = np.sqrt(np.linalg.eigvalsh(np.nan_to_num(covariance))[..., 1])
    sigma[~np.isfinite(covariance).all(axis=(2, 3))] = np.nan
    return UncertaintyMap(camera, range_m, pixels, covariance, sigma)


def _pose_moments(normal: NormalEquations, translation_m: F64, seen: npt.NDArray[np.intp]
                  ) -> tuple[F64, F64, F64]:
    """Over the seen poses, with ``a_p = (1, t_p)``: ``sum_p a_pj C_p B_p^-1`` as ``(G, 24)``,
    ``sum_p a_pj a_pk B_p^-1`` as ``(24, 24)`` (index ``6 j + i``) and the Schur complement."""
    b_inverse, c_b_inverse, schur = normal.factors
    a = np.concatenate([np.ones((len(seen), 1)), translation_m[seen]], axis=1)
    reduce = np.einsum("pj,pgi->gji", a, c_b_inverse[seen]).reshape(len(schur), 24)
    quadratic = np.einsum("pj,pk,pil->jikl", a, a, b_inverse[seen]).reshape(24, 24)
    return reduce, quadratic, schur


def with_left_out(umap: UncertaintyMap, difference_px: F64) -> UncertaintyMap:
    """``umap`` with a model's projection difference ``difference_px`` ``(rows, cols)`` from
    one with the terms it left out added in quadrature, in every direction (the covariance
    gains ``d^2 I``): the parameter covariance holds the errors of the terms a model has, not
    of the ones it lacks, so the difference the missing terms make is stated beside it."""
    extra = np.nan_to_num(difference_px) ** 2
    covariance = umap.covariance + extra[..., None, None] * np.eye(2)
    return UncertaintyMap(umap.camera, umap.range_m, umap.pixels, covariance,
                          np.sqrt(umap.sigma_px ** 2 + extra))


def error_against(problem: Problem, camera: int, true_model: CameraModel, *,
                  true_camera_from_reference: F64, true_reference_from_board: dict[int, F64],
                  range_m: float, pixels: F64) -> F64:
    """Where the true camera images the point the estimate puts at ``pixels`` ``(..., 2)``,
    minus ``pixels``: the error :func:`projection_uncertainty` predicts.

    The point at ``range_m`` on the estimated ray is carried into every board frame by the
    estimated poses and back by the true ones (the mean over the poses both know; NaN
    when they know none in common).
    """
    flat = pixels.reshape(-1, 2)
    state = problem.state
    _in_camera, in_reference, _r = _points_in_reference(problem, camera, flat, range_m)
    seen = [p for p in np.flatnonzero(problem.normal.seen)
            if int(problem.instants[p]) in true_reference_from_board]
    if not seen:
        return np.full(pixels.shape, np.nan)
    total = np.zeros_like(in_reference)
    for p in seen:
        in_board = (in_reference - state.board_translation[p]) @ state.board_rotation[p]
        true = true_reference_from_board[int(problem.instants[p])]
        total += in_board @ true[:3, :3].T + true[:3, 3]
    in_true_reference = total / len(seen)
    in_true_camera = in_true_reference @ true_camera_from_reference[:3, :3].T \
        + true_camera_from_reference[:3, 3]
    error = true_model.project(in_true_camera) - flat
    return np.asarray(error.reshape(pixels.shape), dtype=np.float64)
