"""Whether to estimate the board's warp (:mod:`.warp`), by cross-validation over whole views.

As the lens order (:mod:`.model_order`): the board poses (an even sample of at most
:data:`WARP_POSES`), in time order, are cut into :data:`WARP_FOLDS` contiguous
blocks. For each block the joint problem of the sampled poses is solved again from the flat
solution without the block's views, once with the board held flat and once with its warp
estimated (the project's own bundle: OpenCV cannot fit a warp); each held-out view's
pose alone is then solved with the fitted intrinsics, rig and warp, and its mean squared
reprojection error ``e(v)`` (px²) measured. The warp is chosen when its held-out error is
lower by at least :data:`~.model_order.MIN_GAIN` and the board poses' paired differences
``e_flat(p) - e_warped(p)`` (a pose's views pooled) favour it with a one-sided signed-rank
p (:func:`~.model_order.signed_rank_p`) below :data:`~.model_order.MAX_P_VALUE`. Board poses
are the units, so an error a view's corners share (blur, a pose they pull together) counts
once per pose, not once per corner, and the views a rig's cameras take of one pose count once
together.

The folds start at the flat solution with its inliers and weights: each costs two
Levenberg-Marquardt refinements from nearby, a few solves of the whole problem in all.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from replay.messages import F64

from . import bundle
from .model_order import MAX_P_VALUE, MIN_CORNERS, MIN_GAIN, MIN_ORDER_VIEWS, signed_rank_p
from .normal import refine
from .robust import Problem
from .seed import spread

__all__ = ["WARP_FOLDS", "WARP_POSES", "WarpChoice", "choose_warp"]

WARP_FOLDS = 5
#: the folds refit the problem on an even sample of at most this many board poses: a waved
#: board's neighbouring frames are nearly one pose, and ten solves of every pose were most of
#: its run (held boards give far fewer)
WARP_POSES = 240


@dataclass(frozen=True)
class WarpChoice:
    """The held-out error per board pose ``(P,)`` (px²) with the board flat and warped, the
    relative fall ``gain`` of their sums, the signed-rank ``p_value`` and the outcome;
    without a choice (``why_not``), no errors."""

    flat_px2: F64
    warped_px2: F64
    gain: float
    p_value: float
    folds: int
    why_not: str | None = None

    @property
    def chosen(self) -> bool:
        """Whether the warp is estimated (:data:`~.model_order.MIN_GAIN` and
        :data:`~.model_order.MAX_P_VALUE` met)."""
        return self.why_not is None and self.gain >= MIN_GAIN and self.p_value < MAX_P_VALUE

    @property
    def views(self) -> int:
        """How many held-out board poses were compared (a pose seen by several cameras of
        a rig counts once)."""
        return len(self.flat_px2)

    @property
    def held_out_rms_px(self) -> tuple[float, float]:
        """RMS held-out error (px) flat and warped."""
        return (math.sqrt(float(np.mean(self.flat_px2))) if self.views else math.nan,
                math.sqrt(float(np.mean(self.warped_px2))) if self.views else math.nan)

    def describe(self) -> str:
        """The choice and its evidence in one line."""
        if self.why_not is not None:
            return f"board held flat: warp not cross-validated ({self.why_not})"
        flat, warped = self.held_out_rms_px
        verdict = "estimated" if self.chosen else "held flat"
        return (f"board {verdict} by cross-validation over {self.folds} folds of {self.views} "
                f"board poses: held-out RMS flat {flat:.4f} px, warped {warped:.4f} px; gain "
                f"{100 * self.gain:+.1f} %, p = {self.p_value:.2g} (the warp needs a gain ≥ "
                f"{100 * MIN_GAIN:g} % and p < {MAX_P_VALUE:g})")


def choose_warp(problem: Problem, *, folds: int = WARP_FOLDS) -> WarpChoice:
    """Cross-validate the warp of a flat solution ``problem`` (see the module docstring)."""
    obs = problem.observations
    usable = np.flatnonzero(obs.mask.sum(axis=1) >= MIN_CORNERS)
    if len(usable) < MIN_ORDER_VIEWS:
        return WarpChoice(np.zeros(0), np.zeros(0), math.nan, math.nan, 0,
                          f"{len(usable)} views, fewer than {MIN_ORDER_VIEWS}")
    every = np.unique(obs.instant[usable])
    seen = every[spread(len(every), WARP_POSES)]
    if len(seen) < len(every):  # the views of the poses left out take no part
        kept = np.flatnonzero(~np.isin(obs.instant, np.setdiff1d(every, seen)))
        obs = bundle.Observations(obs.camera[kept], obs.instant[kept], obs.observed[kept],
                                  obs.mask[kept], obs.weight[kept])
        usable = np.flatnonzero(obs.mask.sum(axis=1) >= MIN_CORNERS)
    errors = np.full((2, obs.view_count), math.inf)
    for block in np.array_split(seen, folds):
        held = np.isin(obs.instant, block)
        training = obs.with_mask(obs.mask & ~held[:, None])
        rows = usable[held[usable]]
        for warp in (False, True):
            layout = bundle.Layout.of(problem.layout.setups, problem.state,
                                      corners=problem.layout.corners, warp=warp)
            fit = refine(problem.state, layout, training, problem.points_in_board).state
            errors[int(warp), rows] = _held_out_px2(fit, layout, obs, rows,
                                                    problem.points_in_board)
    measured = usable[np.isfinite(errors[:, usable]).all(axis=0)]
    flat, warped = _per_pose(errors[:, measured], obs.instant[measured],
                             obs.mask[measured].sum(axis=1))
    if len(flat) < MIN_ORDER_VIEWS:
        return WarpChoice(flat, warped, math.nan, math.nan, folds,
                          f"{len(flat)} board poses measured, fewer than {MIN_ORDER_VIEWS}")
    gain = float(1.0 - warped.sum() / flat.sum())
    return WarpChoice(flat, warped, gain, signed_rank_p(flat - warped), folds)


def _per_pose(errors_px2: F64, instants: np.ndarray, corners: np.ndarray) -> tuple[F64, F64]:
    """The views' held-out errors ``(2, V)`` (flat, warped) as one mean squared error per
    board pose (its views' corners pooled): the views a rig's cameras take of one pose share
    that pose's error, so the pose is the unit the signed-rank test counts."""
    _poses, unit = np.unique(instants, return_inverse=True)
    weight = np.bincount(unit, corners.astype(np.float64))
    flat, warped = (np.bincount(unit, e * corners) / weight for e in errors_px2)
    return flat, warped


def _held_out_px2(fit: bundle.RigState, layout: bundle.Layout, obs: bundle.Observations,
                  rows: np.ndarray, points_in_board: F64) -> F64:
    """Mean squared error (px², unweighted) of each view ``rows`` with its pose alone solved
    against ``fit`` (its intrinsics, rig and warp held), one camera at a time."""
    out = np.full(len(rows), math.inf)
    for camera, setup in enumerate(layout.setups):
        mine = np.flatnonzero(obs.camera[rows] == camera)
        if not len(mine):
            continue
        picked = rows[mine]
        camera_from_board = fit.rig_rotation[camera] @ fit.board_rotation[obs.instant[picked]]
        start = bundle.RigState(
            [fit.intrinsics[camera]], np.eye(3)[None], np.zeros((1, 3)), camera_from_board,
            fit.board_translation[obs.instant[picked]] @ fit.rig_rotation[camera].T
            + fit.rig_translation[camera], fit.board_warp_m)
        alone = bundle.Layout.of([bundle.CameraSetup(setup.distortion_model, setup.size, ())],
                                 start, corners=[0])
        views = bundle.Observations(np.zeros(len(picked), np.int64), np.arange(len(picked)),
                                    obs.observed[picked], obs.mask[picked],
                                    np.ones(len(picked)))
        solved = refine(start, alone, views, points_in_board)
        residuals = solved.linearization.residuals
        out[mine] = np.sum(residuals ** 2, axis=(1, 2)) / views.mask.sum(axis=1)
    return out
