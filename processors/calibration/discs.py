"""Where a circle grid's circle is seen: the centroid of its projected disc.

A blob detector reports the area centroid of each dark blob: the centroid of the *image* of
the disc, through the whole lens model. Perspective and distortion stretch the disc
unevenly, so that centroid is not the projection of the circle's centre: in mono_circles'
views (discs 25-40 px across, tilted up to 40 degrees) it is off by up to 0.4 px, the same
way for every board pose, which biases the focal length and distortion (Heikkilä 2000).

The solver therefore predicts what the detector measures. The boundary of a circle of radius
``r`` about the board point ``p`` is ``p + r (cos t, sin t, 0)``; its image ``x(t)`` is a
smooth closed curve, and Green's theorem gives the area and centroid of the region it
encloses as integrals over ``t``:

    A = 1/2 ∮ (u v' - v u') dt,   A ū = 1/2 ∮ u² v' dt,   A v̄ = -1/2 ∮ v² u' dt

with ``x' = d pixel / d point · r (-sin t, cos t, 0)`` from the projection's derivatives. The
trapezoidal rule on a smooth periodic integrand converges geometrically: 12 samples already
agree with the exact centre of the projected ellipse of a pinhole camera to 1e-12 px.

Each round of the solve computes these centroids at the current state, and the solver fits
the projected circle centres to the detections shifted by ``centroid - projected centre``
(:func:`centroid_shifts`): the shift changes slowly with the parameters, so the fixed point
is reached in two or three rounds, and the Jacobian, covariance and uncertainty stay those
of the circle centres.
"""

from __future__ import annotations

import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from . import bundle
from .lens import intrinsics_of, project

#: boundary samples per circle (see the module docstring)
BOUNDARY_SAMPLES = 16


def disc_centroids(distortion_model: str, intrinsics: F64, centres: F64, axes: F64, *,
                   radius_m: float, samples: int = BOUNDARY_SAMPLES) -> tuple[F64, F64]:
    """Projected centres ``(M, 2)`` and area centroids ``(M, 2)`` of the images of discs of
    ``radius_m`` about ``centres`` ``(M, 3)`` in the camera frame, in the plane spanned by
    the unit vectors ``axes`` ``(M, 2, 3)``."""
    angles = 2.0 * np.pi * np.arange(samples) / samples
    cos, sin = np.cos(angles)[None, :, None], np.sin(angles)[None, :, None]
    radial = radius_m * (cos * axes[:, None, 0] + sin * axes[:, None, 1])  # (M, S, 3)
    tangent = radius_m * (-sin * axes[:, None, 0] + cos * axes[:, None, 1])
    points = (centres[:, None, :] + radial).reshape(-1, 3)
    uv, d_point, _ = project(distortion_model, intrinsics, np.vstack([centres, points]))
    m = len(centres)
    centre_px = uv[:m]
    # relative to the projected centre: the integrands stay small, no cancellation
    x = (uv[m:] - np.repeat(centre_px, samples, axis=0)).reshape(m, samples, 2)
    dx = np.einsum("kij,kj->ki", d_point[m:], tangent.reshape(-1, 3)).reshape(m, samples, 2)
    u, v, du, dv = x[..., 0], x[..., 1], dx[..., 0], dx[..., 1]
    area = 0.5 * np.sum(u * dv - v * du, axis=1)
    first_u = 0.5 * np.sum(u * u * dv, axis=1)
    first_v = -0.5 * np.sum(v * v * du, axis=1)
    shift = np.column_stack([first_u, first_v]) / area[:, None]
    return centre_px, centre_px + shift


def view_centroids(model: CameraModel, camera_from_board: F64, points_in_board: F64, *,
                   radius_m: float) -> tuple[F64, F64]:
    """Projected centres ``(M, 2)`` and disc centroids ``(M, 2)`` of circles of ``radius_m``
    about ``points_in_board`` ``(M, 3)``, the board at ``camera_from_board`` (4, 4)."""
    rotation = camera_from_board[:3, :3]
    centres = points_in_board @ rotation.T + camera_from_board[:3, 3]
    axes = np.repeat(rotation[:, :2].T[None], len(points_in_board), axis=0)
    return disc_centroids(model.distortion_model, intrinsics_of(model), centres, axes,
                          radius_m=radius_m)


def centroid_shifts(state: bundle.RigState, layout: bundle.Layout, obs: bundle.Observations,
                    points_in_board: F64, radius_m: float) -> F64:
    """``centroid - projected centre`` ``(V, N, 2)`` of every seen circle at ``state`` (zero
    where unseen): what the detections must be moved by to be circle centres."""
    v_count, n = obs.mask.shape
    out = np.zeros((v_count, n, 2))
    for camera, setup in enumerate(layout.setups):
        views = obs.camera_slices[camera]
        rows = np.arange(views.start, views.stop)
        seen_rows, seen_points = np.nonzero(obs.mask[views])
        if not len(seen_rows):
            continue
        camera_from_board = state.rig_rotation[camera] \
            @ state.board_rotation[obs.instant[rows]]  # (Vc, 3, 3)
        translation = (state.rig_rotation[camera]
                       @ state.board_translation[obs.instant[rows]].T).T \
            + state.rig_translation[camera]
        rotation = camera_from_board[seen_rows]
        centres = np.einsum("kij,kj->ki", rotation, points_in_board[seen_points]) \
            + translation[seen_rows]
        axes = np.swapaxes(rotation[:, :, :2], 1, 2)  # board x and y axes, (K, 2, 3)
        centre_px, centroid_px = disc_centroids(setup.distortion_model,
                                                state.intrinsics[camera], centres, axes,
                                                radius_m=radius_m)
        out[rows[seen_rows], seen_points] = centroid_px - centre_px
    return out

