"""Calibrate N cameras jointly from every view: seed, refine, reject outlier corners, test.

Each camera is seeded by OpenCV's calibration of a sample of its views, every view's board
pose by PnP and every rig transform by the consensus of the instants two cameras share; then
one least-squares problem (:mod:`.bundle`) refines every camera's intrinsics, the rig and
every board pose from every view. Outliers are single corners, as in mrcal: after each solve
a corner whose residual lies beyond ``t`` sigma is left out and the problem solved again,
until the set of outliers is stable. ``t`` makes a false rejection unlikely over the whole
data set (``n exp(-t^2 / 2) = 1/2`` for ``n`` corners: 4.9 sigma at 75 000 corners). A view
that loses most of its corners was not the board (a wrong detection, or two frames of a
stereo pair that show the board at different poses) and is dropped whole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from . import bundle
from .lens import INTRINSIC_NAMES, intrinsics_of, model_of
from .options import TANGENTIAL_P_VALUE, CalibrationOptions, TangentialTest
from .seed import board_pose, rig_transform, seed_model

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]
MIN_VIEWS = 5
#: a view needs this many corners (a board pose has 6 unknowns)
MIN_VIEW_POINTS = 6
#: a view that loses more than this share of its corners to outlier rejection is dropped
VIEW_OUTLIER_SHARE = 0.5
MAX_ROUNDS = 8
MIN_THRESHOLD_SIGMA = 3.0
#: the seed's own errors (px) never make a corner an outlier before the first solve
SEED_FLOOR_PX = 1.0


@dataclass(frozen=True)
class BoardView:
    """Corners ``corners_px`` ``(M, 2)`` of the board points ``point_ids`` ``(M,)`` seen by
    one camera at one instant; views of several cameras at the same instant share a board
    pose. ``weight`` scales the view's residuals (1 / its relative noise)."""

    camera: int
    instant: int
    point_ids: I64
    corners_px: F64
    weight: float = 1.0


@dataclass
class JointResult:
    """Calibrated cameras, rig and board poses, with the evidence and what uncertainty needs.

    ``residuals_px[i]`` ``(M, 2)`` (observed - projected) and ``inliers[i]`` ``(M,)`` follow
    the order of view ``i``'s corners; views in ``rejected`` carry no weight.
    """

    models: list[CameraModel]
    options: list[CalibrationOptions]  # per camera, "auto" tangential resolved
    tangential_tests: list[TangentialTest | None]
    camera_from_reference: list[F64]  # (4, 4) per camera
    reference_from_board: dict[int, F64]  # instant -> (4, 4)
    sigma_px: float  # noise per coordinate, from the residuals
    residuals_px: list[F64]
    inliers: list[B8]
    rejected: dict[int, str]  # view index -> why it carries no weight
    std: list[dict[str, float]]  # per camera, every intrinsic (0 when held)
    #: per camera, covariance (6, 6) of its rig transform: rotation increment (rad, R <-
    #: exp([d]x) R), then translation (m); zero for the reference
    rig_covariance: list[F64]
    problem: Problem
    rounds: int = 0

    @property
    def rms_px(self) -> float:
        """RMS reprojection error (px, 2-D) over the inlier corners."""
        squared = [np.sum(r[m] ** 2) for r, m in zip(self.residuals_px, self.inliers,
                                                      strict=True)]
        count = sum(int(m.sum()) for m in self.inliers)
        return math.sqrt(float(sum(squared)) / max(count, 1))

    def view_rms_px(self, view: int) -> float:
        """RMS error of one view's inlier corners (px)."""
        residual = self.residuals_px[view][self.inliers[view]]
        return math.sqrt(float(np.mean(np.sum(residual ** 2, axis=1)))) if len(residual) \
            else float("nan")

    @property
    def outlier_corners(self) -> int:
        """Corners of used views left out as outliers."""
        return sum(int((~m).sum()) for i, m in enumerate(self.inliers) if i not in self.rejected)


@dataclass
class Problem:
    """The least-squares problem at the solution: enough to propagate its covariance."""

    state: bundle.RigState
    layout: bundle.Layout
    observations: bundle.Observations
    normal: bundle.NormalEquations
    points_in_board: F64
    sigma_px: float
    instants: I64  # original instant number of each pose row
    order: I64 = field(default_factory=lambda: np.zeros(0, np.int64))  # row of each view

    def global_covariance(self) -> F64:
        """Covariance ``(G, G)`` of the global unknowns (intrinsics, rig), board poses
        eliminated: their coupling is included."""
        return self.sigma_px ** 2 * self.normal.global_covariance()


def threshold_sigma(corners: int) -> float:
    """Outlier threshold in sigma for ``corners`` 2-D residuals: one false rejection in two
    data sets of pure Gaussian noise (``P(|r| > t sigma) = exp(-t^2 / 2)``)."""
    return max(MIN_THRESHOLD_SIGMA, math.sqrt(2.0 * math.log(2.0 * max(corners, 1))))


def calibrate_cameras(points_in_board: F64, views: list[BoardView],
                      sizes: list[tuple[int, int]], options: CalibrationOptions, *,
                      seeds: list[CameraModel] | None = None,
                      reject_outliers: bool = True) -> JointResult:
    """Calibrate cameras ``0 .. len(sizes) - 1`` from ``views`` of the board points
    ``points_in_board`` ``(N, 3)``; camera 0 is the rig's reference. ``seeds`` (one model
    per camera) replace OpenCV's seed calibration; without ``reject_outliers`` every corner
    counts."""
    cameras = len(sizes)
    for camera in range(cameras):
        count = sum(v.camera == camera for v in views)
        if count < MIN_VIEWS:
            raise ProcessorError(
                f"too few good views to calibrate{'' if cameras == 1 else f' camera {camera}'}: "
                f"{count} (need at least {MIN_VIEWS}); record more board poses")
    solve_options = options.with_tangential("estimate") \
        if options.tangential == "auto" and options.has_tangential else options
    everything = None if reject_outliers else np.ones((len(views), 1), dtype=bool)
    problem, mask, rejected, rounds = _solve(points_in_board, views, sizes,
                                             [solve_options] * cameras, seeds=seeds,
                                             mask=everything)
    tests: list[TangentialTest | None] = [None] * cameras
    final = [solve_options] * cameras
    if solve_options is not options:
        for camera in range(cameras):
            trial = list(final)
            trial[camera] = options.with_tangential("zero")
            without, *_ = _solve(points_in_board, views, sizes, trial,
                                 state=_without_tangential(problem.state, camera), mask=mask)
            chi2 = (_cost(without) - _cost(problem)) / problem.sigma_px ** 2
            estimated = math.exp(-max(chi2, 0.0) / 2.0) < TANGENTIAL_P_VALUE
            tests[camera] = TangentialTest(chi2, estimated)
        final = [options.with_tangential("estimate" if t is not None and t.estimated else "zero")
                 for t in tests]
        if any(not t.estimated for t in tests if t is not None):
            state = problem.state
            for camera, test in enumerate(tests):
                if test is not None and not test.estimated:
                    state = _without_tangential(state, camera)
            problem, mask, _none, more = _solve(points_in_board, views, sizes, final,
                                                state=state, mask=mask)
            rounds += more
    return _result(problem, views, mask=mask, rejected=rejected, options=final, tests=tests,
                   rounds=rounds)


def _without_tangential(state: bundle.RigState, camera: int) -> bundle.RigState:
    """``state`` with p1 = p2 = 0 for one camera (plumb_bob order: fx fy cx cy k1 k2 p1 p2)."""
    out = state.copy()
    out.intrinsics[camera][6:8] = 0.0
    return out


def _cost(problem: Problem) -> float:
    return float(np.sum(bundle.linearize(problem.state, problem.layout, problem.observations,
                                         problem.points_in_board,
                                         jacobian=False).residuals ** 2))


def _solve(points_in_board: F64, views: list[BoardView], sizes: list[tuple[int, int]],
           options: list[CalibrationOptions], *, seeds: list[CameraModel] | None = None,
           state: bundle.RigState | None = None,
           mask: B8 | None = None) -> tuple[Problem, B8, dict[int, str], int]:
    """Seed (from ``seeds`` or OpenCV, or start at a previous solve's ``state``) and refine;
    reject outlier corners until stable (unless ``mask`` is given, a previous solve's
    inliers by view row, which is then kept)."""
    order = np.argsort([v.camera for v in views], kind="stable")
    instants, instant_rows = np.unique([v.instant for v in views], return_inverse=True)
    n = len(points_in_board)
    observed = np.zeros((len(views), n, 2))
    seen = np.zeros((len(views), n), dtype=bool)
    for row, i in enumerate(order):
        observed[row, views[i].point_ids] = views[i].corners_px
        seen[row, views[i].point_ids] = True
    obs = bundle.Observations(
        camera=np.array([views[i].camera for i in order], dtype=np.int64),
        instant=np.asarray(instant_rows, dtype=np.int64)[order],
        observed=observed, mask=seen.copy(),
        weight=np.array([views[i].weight for i in order], dtype=np.float64))
    if state is None:
        models = seeds or [seed_model(*_camera_views(points_in_board, views, c), sizes[c],
                                      options[c]) for c in range(len(sizes))]
        state = _seed_state(points_in_board, obs, models, len(instants))
    setups = [bundle.CameraSetup(o.distortion_model, s, o.free, o.fix_aspect_ratio)
              for o, s in zip(options, sizes, strict=True)]
    layout = bundle.Layout.of(setups, state)
    rejected: dict[int, str] = {}
    fixed = mask is not None
    dropped = seen.sum(axis=1) < MIN_VIEW_POINTS
    for few in np.flatnonzero(dropped):
        rejected[int(order[few])] = f"{int(seen[few].sum())} corners (need {MIN_VIEW_POINTS})"
    inliers = seen & (mask if mask is not None else True) & ~dropped[:, None]
    if mask is None:
        # gross outliers would drag the first solve away: judge the seed robustly first
        norm = _residual_norms(state, layout, obs.with_mask(seen), points_in_board)
        robust_sigma = float(np.median(norm[inliers])) / math.sqrt(2.0 * math.log(2.0))
        seed_limit = max(threshold_sigma(int(inliers.sum())) * robust_sigma, SEED_FLOOR_PX)
        inliers &= norm <= seed_limit / obs.weight[:, None]
    rounds = 0
    while True:
        rounds += 1
        refinement = bundle.refine(state, layout, obs.with_mask(inliers), points_in_board)
        state = refinement.state
        norm = _residual_norms(state, layout, obs.with_mask(seen), points_in_board)
        count = int(inliers.sum())
        poses = len(np.unique(obs.instant[inliers.any(axis=1)]))
        dof = max(2 * count - layout.global_count - 6 * poses, 1)
        sigma = math.sqrt(float(np.sum((norm * obs.weight[:, None])[inliers] ** 2)) / dof)
        if fixed or rounds >= MAX_ROUNDS:
            break
        limit = threshold_sigma(count) * sigma / obs.weight[:, None]
        new = seen & (norm <= limit) & ~dropped[:, None]
        lost = (seen & ~new).sum(axis=1) > VIEW_OUTLIER_SHARE * seen.sum(axis=1)
        lost |= new.sum(axis=1) < MIN_VIEW_POINTS
        lost &= ~dropped
        dropped |= lost
        for bad in np.flatnonzero(lost):
            view = int(order[bad])
            rejected[view] = (f"{int((seen[bad] & ~new[bad]).sum())} of {int(seen[bad].sum())} "
                              "corners beyond the outlier threshold: not the board at one pose")
        new[lost] = False
        if np.array_equal(new, inliers):
            break
        inliers = new
    # the last refinement saw exactly these inliers: its normal equations are the problem's
    problem = Problem(state, layout, obs.with_mask(inliers), refinement.normal, points_in_board,
                      sigma, instants, order)
    return problem, inliers, rejected, rounds


def _residual_norms(state: bundle.RigState, layout: bundle.Layout, obs: bundle.Observations,
                    points_in_board: F64) -> F64:
    """Length ``(V, N)`` of every corner's unweighted residual (px)."""
    residual = bundle.linearize(state, layout, obs, points_in_board, jacobian=False).residuals
    return np.asarray(np.linalg.norm(residual, axis=2) / obs.weight[:, None])


def _camera_views(points_in_board: F64, views: list[BoardView], camera: int
                  ) -> tuple[list[F64], list[F64]]:
    mine = [v for v in views if v.camera == camera]
    return [points_in_board[v.point_ids] for v in mine], [v.corners_px for v in mine]


def _seed_state(points_in_board: F64, obs: bundle.Observations, models: list[CameraModel],
                instant_count: int) -> bundle.RigState:
    """Board poses by PnP; each instant from the lowest-numbered camera that saw it; rig
    transforms by consensus over the instants a camera shares with the reference."""
    poses: dict[tuple[int, int], F64] = {}
    for row in range(obs.view_count):
        ids = np.flatnonzero(obs.mask[row])
        if len(ids) < MIN_VIEW_POINTS:
            continue
        pose = board_pose(points_in_board[ids], obs.observed[row, ids],
                          models[int(obs.camera[row])])
        if pose is not None:
            poses[(int(obs.camera[row]), int(obs.instant[row]))] = pose
    cameras = len(models)
    rig = [np.eye(4)]
    for camera in range(1, cameras):
        shared = [i for (c, i) in poses if c == camera and (0, i) in poses]
        rig.append(rig_transform([poses[(camera, i)] for i in shared],
                                 [poses[(0, i)] for i in shared]))
    board = np.tile(np.eye(4), (instant_count, 1, 1))
    for instant in range(instant_count):
        for camera in range(cameras):
            if (camera, instant) in poses:
                board[instant] = np.linalg.inv(rig[camera]) @ poses[(camera, instant)]
                break
    return bundle.RigState([intrinsics_of(m) for m in models],
                           np.stack([r[:3, :3] for r in rig]), np.stack([r[:3, 3] for r in rig]),
                           board[:, :3, :3].copy(), board[:, :3, 3].copy())


def _result(problem: Problem, views: list[BoardView], *, mask: B8, rejected: dict[int, str],
            options: list[CalibrationOptions], tests: list[TangentialTest | None],
            rounds: int) -> JointResult:
    state, layout, obs = problem.state, problem.layout, problem.observations
    models = [model_of(s.distortion_model, i, s.size)
              for s, i in zip(layout.setups, state.intrinsics, strict=True)]
    residual = bundle.linearize(state, layout, obs.with_mask(np.ones_like(mask)),
                                problem.points_in_board, jacobian=False).residuals
    residual = residual / obs.weight[:, None, None]
    residuals, inliers = [np.zeros((0, 2))] * len(views), [np.zeros(0, bool)] * len(views)
    for row, view in enumerate(problem.order):
        ids = views[view].point_ids
        residuals[view] = -residual[row, ids]
        inliers[view] = mask[row, ids]
    covariance = problem.global_covariance()
    std = []
    for camera, setup in enumerate(layout.setups):
        columns = layout.intrinsic_columns[camera]
        basis = layout.bases[camera]
        full = basis @ covariance[np.ix_(columns, columns)] @ basis.T
        std.append(dict(zip(INTRINSIC_NAMES[setup.distortion_model],
                            np.sqrt(np.maximum(np.diag(full), 0.0)).tolist(), strict=True)))
    rig_covariance = [covariance[np.ix_(layout.rig_columns[c], layout.rig_columns[c])]
                      if c else np.zeros((6, 6)) for c in range(len(models))]
    return JointResult(
        models=models, options=options, tangential_tests=tests, rig_covariance=rig_covariance,
        camera_from_reference=[state.camera_from_reference(c) for c in range(len(models))],
        reference_from_board={int(problem.instants[p]): state.reference_from_board(p)
                              for p in range(len(problem.instants))},
        sigma_px=problem.sigma_px, residuals_px=residuals, inliers=inliers, rejected=rejected,
        std=std, problem=problem, rounds=rounds)
