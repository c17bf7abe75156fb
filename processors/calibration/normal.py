"""The normal equations of the joint refinement (:mod:`.bundle`) and the Levenberg-Marquardt
refinement over them.

``J^T J`` is an arrow: a small global block, one 6 x 6 block per board pose and their
coupling. A step eliminates the pose blocks (Schur complement); the same blocks give the
covariance of the global unknowns. The views are linearized :data:`~.bundle.CHUNK_VIEWS` at a
time and their products summed, so a long log's Jacobian is never held whole.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from replay.messages import F64

from .bundle import (
    B8,
    Layout,
    Linearization,
    Observations,
    RigState,
    linearize,
    residuals_only,
    view_chunks,
)

#: LM stops when a step lowers the cost by less than this fraction
TOLERANCE = 1e-12
MAX_ITERATIONS = 60


@dataclass
class NormalEquations:
    """``J^T J`` in blocks: ``a`` (G, G) global, ``c`` (P, G, 6) coupling, ``b`` (P, 6, 6) per
    board pose; gradient ``g_global`` (G,), ``g_pose`` (P, 6). Poses no corner sees get an
    identity block (their increment stays zero)."""

    a: F64
    c: F64
    b: F64
    g_global: F64
    g_pose: F64
    seen: B8  # (P,)

    def damped_solve(self, damping: float) -> tuple[F64, F64]:
        """Levenberg-Marquardt increments ``(G,)``, ``(P, 6)`` with Marquardt's scaling."""
        a = self.a + damping * np.diag(np.diag(self.a))
        b = self.b + damping * self.b * np.eye(6)
        d_global, d_pose = _schur_solve(_schur_factors(a, self.c, b), self.c,
                                        -self.g_global[:, None], -self.g_pose[:, :, None])
        return d_global[:, 0], d_pose[:, :, 0]

    def solve(self, rhs_global: F64, rhs_pose: F64) -> tuple[F64, F64]:
        """``(J^T J)^-1 rhs`` for right-hand sides ``(G, R)`` and ``(P, 6, R)`` (the pose
        blocks' inverses and the Schur complement are computed at the first call)."""
        return _schur_solve(self.factors, self.c, rhs_global, rhs_pose)

    @cached_property
    def factors(self) -> tuple[F64, F64, F64]:
        """The pose blocks' inverses ``(P, 6, 6)``, the coupling times them ``(P, G, 6)`` and
        the Schur complement ``(G, G)`` (computed at the first use)."""
        return _schur_factors(self.a, self.c, self.b)

    def with_prior(self, solved_px: F64, stated_px: F64, prior_residual: F64) -> NormalEquations:
        """The same equations with the prior's weights ``solved_px`` ``(G,)`` replaced by
        ``stated_px``, at the point where the prior's residuals are ``prior_residual`` (a
        copy)."""
        a = self.a.copy()
        a[np.diag_indices(len(a))] += stated_px ** 2 - solved_px ** 2
        values = np.divide(prior_residual, solved_px, out=np.zeros_like(solved_px),
                           where=solved_px > 0)
        gradient = self.g_global + (stated_px ** 2 - solved_px ** 2) * values
        return NormalEquations(a, self.c, self.b, gradient, self.g_pose, self.seen)

    def global_covariance(self) -> F64:
        """``[(J^T J)^-1]`` of the global unknowns ``(G, G)`` (times sigma^2: covariance)."""
        b_inverse = np.linalg.inv(self.b)
        schur = self.a - np.einsum("pgi,pij,phj->gh", self.c, b_inverse, self.c)
        inverse: F64 = np.linalg.inv(schur)
        return inverse


def _schur_factors(a: F64, c: F64, b: F64) -> tuple[F64, F64, F64]:
    """The pose blocks' inverses ``(P, 6, 6)``, ``c`` times them ``(P, G, 6)`` and the Schur
    complement ``(G, G)``."""
    b_inverse = np.asarray(np.linalg.inv(b), dtype=np.float64)
    c_b_inverse: F64 = np.einsum("pgi,pij->pgj", c, b_inverse)
    schur: F64 = a - np.einsum("pgj,phj->gh", c_b_inverse, c)
    return b_inverse, c_b_inverse, schur


def _schur_solve(factors: tuple[F64, F64, F64], c: F64, rhs_global: F64, rhs_pose: F64
                 ) -> tuple[F64, F64]:
    b_inverse, c_b_inverse, schur = factors
    reduced = rhs_global - np.einsum("pgj,pjr->gr", c_b_inverse, rhs_pose)
    x_global = np.linalg.solve(schur, reduced) if len(schur) \
        else np.zeros((0, rhs_pose.shape[2]))
    x_pose = np.einsum("pij,pjr->pir", b_inverse,
                       rhs_pose - np.einsum("pgi,gr->pir", c, x_global))
    return x_global, x_pose


def normal_equations(lin: Linearization, layout: Layout, obs: Observations,
                     pose_count: int) -> NormalEquations:
    """The blocks of ``J^T J`` and ``J^T r`` at a linearization."""
    normal = _no_equations(layout.global_count, pose_count)
    _add_views(normal, lin, layout, obs)
    return _finished(normal, layout, lin.prior)


def _no_equations(global_count: int, pose_count: int) -> NormalEquations:
    g = global_count
    return NormalEquations(np.zeros((g, g)), np.zeros((pose_count, g, 6)),
                           np.zeros((pose_count, 6, 6)), np.zeros(g), np.zeros((pose_count, 6)),
                           np.zeros(pose_count, dtype=bool))


def _add_views(normal: NormalEquations, lin: Linearization, layout: Layout,
               obs: Observations) -> None:
    """Add the products of the views of ``lin`` (at ``obs``) to ``normal``."""
    pose_count = len(normal.b)
    r = lin.residuals.reshape(obs.view_count, -1)  # (V, 2N)
    pose_t = np.swapaxes(lin.pose, 1, 2)  # (V, 6, 2N)
    np.add.at(normal.b, obs.instant, pose_t @ lin.pose)
    np.add.at(normal.g_pose, obs.instant, np.einsum("vir,vr->vi", pose_t, r))
    for camera, (views, block) in enumerate(zip(obs.slices_of(len(layout.setups)),
                                                lin.global_blocks, strict=True)):
        columns = layout.global_columns(camera)
        if not len(columns) or views.stop == views.start:
            continue
        flat = block.reshape(-1, block.shape[2])
        normal.a[np.ix_(columns, columns)] += flat.T @ flat
        normal.g_global[columns] += flat.T @ r[views].reshape(-1)
        coupling = np.swapaxes(block, 1, 2) @ lin.pose[views]  # (Vc, G_c, 6)
        per_pose = np.zeros((pose_count, len(columns), 6))
        np.add.at(per_pose, obs.instant[views], coupling)
        normal.c[:, columns, :] += per_pose


def _finished(normal: NormalEquations, layout: Layout, prior_residual: F64) -> NormalEquations:
    """``normal`` with the prior added and unseen poses given an identity block."""
    if len(prior_residual):
        normal.a[np.diag_indices(layout.global_count)] += layout.prior_px ** 2
        normal.g_global += layout.prior_px * prior_residual
    normal.seen = np.abs(normal.b).sum(axis=(1, 2)) > 0
    normal.b[~normal.seen] = np.eye(6)
    return normal


def linearized_equations(state: RigState, layout: Layout, obs: Observations,
                         points_in_board: F64, pose_count: int
                         ) -> tuple[Linearization, NormalEquations]:
    """The residuals (no Jacobian blocks) and normal equations at ``state``, the views
    linearized :data:`CHUNK_VIEWS` at a time."""
    v_count, n = obs.mask.shape
    residuals = np.empty((v_count, n, 2))
    normal = _no_equations(layout.global_count, pose_count)
    for rows in view_chunks(v_count):
        part = obs.rows(rows)
        lin = linearize(state, layout, part, points_in_board)
        residuals[rows] = lin.residuals
        _add_views(normal, lin, layout, part)
    prior_residual = layout.prior_residual(state)
    return (residuals_only(residuals, layout, prior_residual),
            _finished(normal, layout, prior_residual))


@dataclass
class Refinement:
    """The refined state, its residuals (``linearization`` holds no Jacobian blocks) and
    normal equations, and how it got there."""

    state: RigState
    linearization: Linearization
    normal: NormalEquations
    iterations: int
    costs: list[float] = field(default_factory=list)


def refine(seed: RigState, layout: Layout, obs: Observations, points_in_board: F64, *,
           max_iterations: int = MAX_ITERATIONS) -> Refinement:
    """Levenberg-Marquardt from ``seed`` to the least-squares optimum."""
    pose_count = len(seed.board_rotation)
    state = seed
    lin, normal = linearized_equations(state, layout, obs, points_in_board, pose_count)
    damping = 1e-6
    costs = [lin.cost]
    iteration = 0
    for iteration in range(1, max_iterations + 1):  # noqa: B007
        d_global, d_pose = normal.damped_solve(damping)
        trial = layout.step(state, d_global, d_pose)
        trial_lin, trial_normal = linearized_equations(trial, layout, obs, points_in_board,
                                                       pose_count)
        if not np.isfinite(trial_lin.cost) or trial_lin.cost > lin.cost:
            damping *= 10.0
            if damping > 1e12:
                break
            continue
        improvement = lin.cost - trial_lin.cost
        state, lin, normal = trial, trial_lin, trial_normal
        costs.append(lin.cost)
        damping = max(damping / 10.0, 1e-12)
        if improvement <= TOLERANCE * max(lin.cost, 1e-300):
            break
    return Refinement(state, lin, normal, iteration, costs)
