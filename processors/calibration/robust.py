"""One robust solve: seed, refine, leave out outlier corners, weight blurred views down.

Outliers are single corners, as in mrcal: after each solve a corner whose residual lies
beyond ``t`` sigma is left out and the problem solved again, until the set of outliers is
stable. ``t`` makes a false rejection unlikely over the whole data set (``n exp(-t^2 / 2) =
1/2`` for ``n`` corners: 4.9 sigma at 75 000 corners). A view that loses most of its corners
was not the board (a wrong detection, or two frames of a stereo pair that show the board at
different poses) and is dropped whole. Once the solve has settled, such views are given one
more chance: posed afresh through the solution's lens and solved with the others, a view that
only its seed pose could not explain (PnP through a seed lens can pick the wrong one of a
planar board's two poses) fits and stays; one that is not the board is dropped again, and
the solve before the trial stands. Views of several cameras at one instant share a board
pose only while they agree on it: frames stamped as one instant but exposed apart (cameras
that are not synchronised) see a moving board at two poses. Such a view is given a board
pose of its own, and so stays in its camera's intrinsics while the pair leaves the rig
(``split``: "not simultaneous: the board moved N mm between the two images"): when it would
lose most of its corners with the shared pose, and, once the solve has settled, when its
own pose explains its corners better than noise would (a likelihood ratio, chi-square with
6 degrees of freedom, at one false split in a hundred data sets). Views of a moving board carry
their speed; after the first solve the blur law of :mod:`.motion` is fitted to their
residuals, weights them and leaves out views too blurred to help. The centres of a circle
grid's circles are measured as the centroids of their images; each round moves them by the
shift :mod:`.discs` computes at the current solution, until the shift settles.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from . import bundle, normal
from .discs import centroid_shifts
from .lens import model_of
from .motion import BlurModel, fit_blur
from .normal import NormalEquations
from .options import CalibrationOptions
from .seed import board_pose, seed_model, seed_state

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]
#: a view needs this many corners (a board pose has 6 unknowns)
MIN_VIEW_POINTS = 6
#: a view that loses more than this share of its corners to outlier rejection is dropped
VIEW_OUTLIER_SHARE = 0.5
MAX_ROUNDS = 8
MIN_THRESHOLD_SIGMA = 3.0
#: the seed's own errors (px) never make a corner an outlier before the first solve
SEED_FLOOR_PX = 1.0
#: the circle centres' shifts of two rounds agree within this (px): the fixed point is reached
SHIFT_TOLERANCE_PX = 1e-4
#: views taken back in are kept only if the noise estimate grows by at most this factor
RETRY_SIGMA_GROWTH = 1.25
#: rounds of splitting views that disagree with their instant's pose, at most
MAX_SPLIT_STAGES = 5
#: views split from their instant by chance, in a data set whose views all agree: one in a
#: hundred data sets (a split costs the rig a joint view; a pair left in costs it more)
FALSE_SPLITS = 0.01
#: Gauss-Newton steps of a view's own pose
OWN_POSE_ITERATIONS = 6


@dataclass(frozen=True)
class BoardView:
    """Corners ``corners_px`` ``(M, 2)`` of the board points ``point_ids`` ``(M,)`` seen by
    one camera at one instant; views of several cameras at the same instant share a board
    pose. ``weight`` scales the view's residuals (1 / its relative noise); ``speed_px`` is
    how far the board moved in the image between frames (0: held still)."""

    camera: int
    instant: int
    point_ids: I64
    corners_px: F64
    weight: float = 1.0
    speed_px: float = 0.0


@dataclass
class InlierSelection:
    """What a robust solve decided about the data: the views' rows (ordered by camera), the
    observations with their weights, the inlier corners, the views left out and why, and the
    blur law (None when the views show none)."""

    order: I64  # view index of each row
    instants: I64  # instant number of each board pose row
    observations: bundle.Observations  # mask: every corner seen; weights: final
    inliers: B8  # (V, N)
    rejected: dict[int, str] = field(default_factory=dict)  # view index -> why
    blur: BlurModel | None = None
    blurred: int = 0  # views left out as too blurred
    outlying: set[int] = field(default_factory=set)  # views left out as not the board
    #: views given a board pose of their own: view index -> the pose row they shared
    split_from: dict[int, int] = field(default_factory=dict)
    split: dict[int, str] = field(default_factory=dict)  # view index -> why

    @classmethod
    def of(cls, views: list[BoardView], points_in_board: F64) -> InlierSelection:
        """Every corner of ``views`` an inlier; views with too few corners left out."""
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
            instant=np.asarray(instant_rows, dtype=np.int64).reshape(-1)[order],
            observed=observed, mask=seen,
            weight=np.array([views[i].weight for i in order], dtype=np.float64))
        evidence = cls(order, instants, obs, seen.copy())
        for few in np.flatnonzero(seen.sum(axis=1) < MIN_VIEW_POINTS):
            evidence.drop(int(few), f"{int(seen[few].sum())} corners (need {MIN_VIEW_POINTS})")
        return evidence

    def drop(self, row: int, why: str) -> None:
        """Leave one view out."""
        self.inliers[row] = False
        self.rejected[int(self.order[row])] = why

    def restore(self, row: int) -> None:
        """Take a view left out as not the board back in, every corner it shows an inlier."""
        view = int(self.order[row])
        self.rejected.pop(view, None)
        self.outlying.discard(view)
        self.inliers[row] = self.observations.mask[row]

    @property
    def dropped(self) -> B8:
        """``(V,)`` whether each row's view is left out."""
        return np.isin(self.order, list(self.rejected))

    def partnered(self, row: int) -> bool:
        """Whether another view in use shares the row's board pose."""
        obs = self.observations
        return bool(np.any((obs.instant == obs.instant[row]) & ~self.dropped
                           & (np.arange(obs.view_count) != row)))

    def split_off(self, row: int, state: bundle.RigState,
                  reference_from_board: F64) -> bundle.RigState:
        """Give the row's view a board pose of its own, ``reference_from_board`` (4, 4): a new
        pose row (numbered after every instant); the state with it."""
        obs = self.observations
        view = int(self.order[row])
        self.split_from.setdefault(view, int(obs.instant[row]))
        obs.instant[row] = len(self.instants)
        self.instants = np.append(self.instants, int(self.instants.max()) + 1)
        out = state.copy()
        out.board_rotation = np.concatenate([state.board_rotation,
                                             reference_from_board[None, :3, :3]])
        out.board_translation = np.concatenate([state.board_translation,
                                                reference_from_board[None, :3, 3]])
        return out


@dataclass
class Problem:
    """The least-squares problem at the solution: enough to propagate its covariance."""

    state: bundle.RigState
    layout: bundle.Layout
    observations: bundle.Observations  # masked to the inliers; circle centres, not centroids
    normal: normal.NormalEquations
    points_in_board: F64
    sigma_px: float
    instants: I64  # original instant number of each pose row
    order: I64  # view index of each row

    @cached_property
    def stated_normal(self) -> NormalEquations:
        """The normal equations with the prior at its stated width (:func:`.prior.stated_weights`),
        not the solve's pull: the stated uncertainty is propagated through them."""
        layout = self.layout
        return self.normal.with_prior(layout.prior_px, layout.stated_prior_px,
                                      layout.prior_residual(self.state))

    def at_stated_prior(self) -> bundle.RigState:
        """The solution at the prior's stated width: one Gauss-Newton step from this one."""
        return self.layout.step(self.state, *self.stated_normal.damped_solve(0.0))

    def global_covariance(self) -> F64:
        """Covariance ``(G, G)`` of the global unknowns (intrinsics, rig), board poses
        eliminated: their coupling is included."""
        return self.sigma_px ** 2 * self.stated_normal.global_covariance()

    @property
    def cost(self) -> float:
        """Sum of squared (weighted) residuals of the inliers."""
        return float(np.sum(bundle.linearize(self.state, self.layout, self.observations,
                                             self.points_in_board,
                                             jacobian=False).residuals ** 2))


def threshold_sigma(corners: int) -> float:
    """Outlier threshold in sigma for ``corners`` 2-D residuals: one false rejection in two
    data sets of pure Gaussian noise (``P(|r| > t sigma) = exp(-t^2 / 2)``)."""
    return max(MIN_THRESHOLD_SIGMA, math.sqrt(2.0 * math.log(2.0 * max(corners, 1))))


@dataclass(frozen=True)
class BoardViews:
    """What a solve fits: views of the board points ``points_in_board`` ``(N, 3)`` by cameras
    whose images are ``sizes`` (width, height) each. With ``disc_diameter_m`` the points are
    centres of circles that diameter across, and the views show the centroids of their
    images (a circle grid's detections)."""

    points_in_board: F64
    views: list[BoardView]
    sizes: list[tuple[int, int]]
    disc_diameter_m: float | None = None


def camera_views(views: list[BoardView], camera: int) -> list[int]:
    """Indices of the views of ``camera``, in order."""
    return [i for i, v in enumerate(views) if v.camera == camera]


def seed_camera(points_in_board: F64, views: list[BoardView], camera: int,
                size: tuple[int, int], options: CalibrationOptions) -> CameraModel:
    """OpenCV's calibration of one camera's views (:func:`~.seed.seed_model`)."""
    mine = [views[i] for i in camera_views(views, camera)]
    return seed_model([points_in_board[v.point_ids] for v in mine],
                      [v.corners_px for v in mine], size, options)


def robust_solve(data: BoardViews, options: list[CalibrationOptions], *,
                 seeds: list[CameraModel] | None = None, state: bundle.RigState | None = None,
                 evidence: InlierSelection | None = None, reject: bool = True, warp: bool = False
                 ) -> tuple[Problem, InlierSelection, int]:
    """Seed (from ``seeds`` or OpenCV, or start at a previous solve's ``state``) and refine
    one camera's ``options`` each; with ``warp`` the board's warp too (:mod:`.warp`).

    Without ``evidence`` outliers and blur are decided here (unless ``reject`` is off); with
    a previous solve's ``evidence`` its inliers and weights are kept.
    """
    points_in_board, views, sizes = data.points_in_board, data.views, data.sizes
    disc_diameter_m = data.disc_diameter_m
    fresh = evidence is None
    evidence = evidence or InlierSelection.of(views, points_in_board)
    obs = evidence.observations
    if state is None:
        models = seeds or [seed_camera(points_in_board, views, c, sizes[c], options[c])
                           for c in range(len(sizes))]
        state = seed_state(points_in_board, obs, models, len(evidence.instants),
                           min_points=MIN_VIEW_POINTS)
    setups = [bundle.CameraSetup(o.distortion_model, s, o.free, o.fix_aspect_ratio)
              for o, s in zip(options, sizes, strict=True)]
    layout = bundle.Layout.of(setups, state, corners=obs.corners(len(setups)), warp=warp)

    def shift_at(at: bundle.RigState) -> F64:
        """What moves the observations onto the points' projections at ``at``."""
        if disc_diameter_m is None:
            return np.zeros_like(obs.observed)
        return -centroid_shifts(at, layout, obs, points_in_board, disc_diameter_m / 2.0)

    shift = shift_at(state)
    if fresh and reject:
        # gross outliers would drag the first solve away: judge the seed robustly first
        norm = _residual_norms(state, layout, _moved(obs, shift), points_in_board)
        # a corner the seed cannot project (NaN) is no inlier and says nothing of the noise
        evidence.inliers &= np.isfinite(norm)
        projected = norm[evidence.inliers]
        robust_sigma = float(np.median(projected)) / math.sqrt(2 * math.log(2)) \
            if len(projected) else 0.0
        limit = max(SEED_FLOOR_PX, threshold_sigma(int(evidence.inliers.sum())) * robust_sigma)
        evidence.inliers &= norm <= limit / obs.weight[:, None]
        # a view left with too few corners cannot hold its pose in the first solve (a single
        # corner leaves it singular): it sits that solve out and is judged after it
        evidence.inliers[evidence.inliers.sum(axis=1) < MIN_VIEW_POINTS] = False
    speeds = np.array([views[i].speed_px for i in evidence.order])
    lenses = [(o.distortion_model, s) for o, s in zip(options, sizes, strict=True)]
    rounds, trial, splits, lost_stages = 0, None, 0, 0
    while True:
        rounds += 1
        refinement = normal.refine(state, layout,
                                   _moved(obs, shift).with_mask(evidence.inliers),
                                   points_in_board)
        state = refinement.state
        previous, shift = shift, shift_at(state)
        settled = float(np.abs(shift - previous).max(initial=0.0)) <= SHIFT_TOLERANCE_PX
        norm = _residual_norms(state, layout, _moved(obs, shift), points_in_board)
        sigma = _sigma(norm * obs.weight[:, None], evidence.inliers, layout)
        if rounds >= MAX_ROUNDS * ((1 if trial is None else 2) + splits + lost_stages):
            break
        if not (fresh and reject):
            if settled:
                break
            continue
        if rounds == 1 and np.any(speeds > 0) and _weigh_blur(evidence, norm, speeds):
            continue
        changed, lost = _reject_outliers(evidence, norm, sigma)
        if lost:  # views that lose most of their corners to a shared pose get their own
            state = _split_lost(evidence, state, _moved(obs, shift), points_in_board,
                                lenses=lenses, rows=lost)
            lost_stages += 1
            continue
        if not changed and settled:
            if trial is None and splits < MAX_SPLIT_STAGES:
                state, split = _split_disagreeing(evidence, state, layout=layout,
                                                  obs=_moved(obs, shift),
                                                  points_in_board=points_in_board, sigma=sigma)
                if split:
                    splits += 1
                    continue
            if trial is not None or not evidence.outlying:
                break
            trial = _Trial.before(state, refinement, sigma, shift, evidence)
            state, restored = _retry_outlying(evidence, state, _moved(obs, shift),
                                              points_in_board, lenses)
            if not restored:
                trial = None
                break
    if trial is not None and not trial.holds(evidence, state, sigma):
        state, refinement, sigma, shift = trial.undo(evidence)
    _word_splits(evidence, state, points_in_board)
    problem = Problem(state, layout, _moved(obs, shift).with_mask(evidence.inliers),
                      refinement.normal, points_in_board, sigma, evidence.instants,
                      evidence.order)
    return problem, evidence, rounds


def _sigma(weighted_norm: F64, inliers: B8, layout: bundle.Layout) -> float:
    """Noise per coordinate at unit weight, from the inlier residuals (dof corrected)."""
    count = int(inliers.sum())
    dof = max(2 * count - layout.global_count - 6 * int(inliers.any(axis=1).sum()), 1)
    return math.sqrt(float(np.sum(weighted_norm[inliers] ** 2)) / dof)


def _reject_outliers(evidence: InlierSelection, norm: F64, sigma: float
                     ) -> tuple[bool, list[int]]:
    """Mark the corners beyond the threshold (and drop views that lose most of theirs);
    whether anything changed, and the rows that lost most of their corners to a board pose
    they share with another view in use (not dropped: they get a pose of their own, their
    corners left as they were)."""
    obs, seen = evidence.observations, evidence.observations.mask
    dropped = evidence.dropped
    limit = threshold_sigma(int(evidence.inliers.sum())) * sigma / obs.weight[:, None]
    new = seen & (norm <= limit) & ~dropped[:, None]
    lost = ((seen & ~new).sum(axis=1) > VIEW_OUTLIER_SHARE * seen.sum(axis=1)) \
        | (new.sum(axis=1) < MIN_VIEW_POINTS)
    lost &= ~dropped
    shared = [int(row) for row in np.flatnonzero(lost) if evidence.partnered(int(row))]
    if shared:
        return True, shared
    changed = not np.array_equal(new, evidence.inliers) or bool(lost.any())
    evidence.inliers = new
    for row in np.flatnonzero(lost):
        evidence.drop(int(row), f"{int((seen[row] & ~new[row]).sum())} of "
                      f"{int(seen[row].sum())} corners beyond the outlier threshold: not the "
                      "board at one pose")
        evidence.outlying.add(int(evidence.order[row]))
    return changed, []


def _split_lost(evidence: InlierSelection, state: bundle.RigState, obs: bundle.Observations,
                points_in_board: F64, *, lenses: list[tuple[str, tuple[int, int]]],
                rows: list[int]) -> bundle.RigState:
    """Give each of ``rows`` a board pose of its own, found by PnP through its camera's
    current lens (a view PnP cannot pose is dropped as not the board)."""
    for row in rows:
        camera = int(obs.camera[row])
        ids = np.flatnonzero(obs.mask[row])
        distortion_model, size = lenses[camera]
        camera_from_board = board_pose(points_in_board[ids], obs.observed[row, ids],
                                       model_of(distortion_model, state.intrinsics[camera],
                                                size))
        if camera_from_board is None:
            evidence.drop(row, "not the board at one pose: no pose fits its corners")
            evidence.outlying.add(int(evidence.order[row]))
            continue
        state = evidence.split_off(row, state, np.linalg.inv(
            state.camera_from_reference(camera)) @ camera_from_board)
        evidence.inliers[row] = obs.mask[row]
    return state


def _own_poses(state: bundle.RigState, layout: bundle.Layout, obs: bundle.Observations,
               points_in_board: F64, rows: I64) -> tuple[bundle.RigState, F64, F64]:
    """Each of ``rows``' views with a board pose of its own (Gauss-Newton from the pose it
    shares, its camera held): those poses (one per row, in a state of their own), and each
    row's cost (sum of squared weighted residuals) with the shared pose and with its own."""
    part = bundle.Observations(obs.camera[rows], np.arange(len(rows)), obs.observed[rows],
                               obs.mask[rows], obs.weight[rows])
    own = state.copy()
    own.board_rotation = state.board_rotation[obs.instant[rows]].copy()
    own.board_translation = state.board_translation[obs.instant[rows]].copy()
    no_global = np.zeros(layout.global_count)

    def costs(at: bundle.RigState) -> F64:
        residuals = bundle.linearize(at, layout, part, points_in_board,
                                     jacobian=False).residuals
        return np.asarray(np.sum(residuals.reshape(len(rows), -1) ** 2, axis=1))

    shared = costs(own)
    best = shared.copy()
    for _ in range(OWN_POSE_ITERATIONS):
        lin = bundle.linearize(own, layout, part, points_in_board)
        jacobian = lin.pose  # (R, 2N, 6)
        hessian = np.swapaxes(jacobian, 1, 2) @ jacobian + 1e-9 * np.eye(6)
        gradient = np.einsum("rki,rk->ri", jacobian, lin.residuals.reshape(len(rows), -1))
        step = -np.linalg.solve(hessian, gradient[:, :, None])[:, :, 0]
        trial = layout.step(own, no_global, step)
        cost = costs(trial)
        better = cost < best
        own.board_rotation[better] = trial.board_rotation[better]
        own.board_translation[better] = trial.board_translation[better]
        best = np.where(better, cost, best)
    return own, shared, best


def _split_disagreeing(evidence: InlierSelection, state: bundle.RigState, *,
                       layout: bundle.Layout, obs: bundle.Observations, points_in_board: F64,
                       sigma: float) -> tuple[bundle.RigState, bool]:
    """Views that disagree with their instant's board pose beyond noise given a pose of
    their own: the likelihood ratio of a pose each against the one shared is chi-square
    with 6 degrees of freedom per extra pose. An instant beyond :data:`FALSE_SPLITS` false
    splits per data set is split; when none is, but the instants together are (many pairs a
    little apart: the rig, fitted to them, hides each one's misfit), those that gain most
    are split until the rest agree. The instant that agrees best is never split: the rig
    rests on it (the flow warns when it rests on few). In an instant split, the view whose
    own pose gains most is given it. The state, and whether any was."""
    inliers = obs.with_mask(evidence.inliers)
    in_use = ~evidence.dropped & (evidence.inliers.sum(axis=1) >= MIN_VIEW_POINTS)
    counts = np.bincount(obs.instant[in_use], minlength=len(evidence.instants))
    rows = np.flatnonzero(in_use & (counts[obs.instant] >= 2))
    if not len(rows) or not sigma > 0:
        return state, False
    own, shared, alone = _own_poses(state, layout, inliers, points_in_board, rows)
    gain = (shared - alone) / sigma ** 2
    instants = obs.instant[rows]
    tested = np.unique(instants)
    members = [np.flatnonzero(instants == instant) for instant in tested]
    gains = np.array([float(gain[m].sum()) for m in members])
    dofs = np.array([6 * (len(m) - 1) for m in members])
    chosen = [i for i in range(len(tested))
              if chi2_survival(float(gains[i]), int(dofs[i])) < FALSE_SPLITS / len(tested)]
    if not chosen:
        total, dof = float(gains.sum()), int(dofs.sum())
        for i in np.argsort(-gains).tolist():
            if chi2_survival(total, dof) >= FALSE_SPLITS:
                break
            chosen.append(i)
            total, dof = total - float(gains[i]), dof - int(dofs[i])
    if len(chosen) == len(tested):  # the rig rests on the one that agrees best
        chosen.remove(int(np.argmin(gains)))
    for i in chosen:
        pick = members[i][int(np.argmax(gain[members[i]]))]
        state = evidence.split_off(int(rows[pick]), state, own.reference_from_board(int(pick)))
    return state, bool(chosen)


def chi2_survival(x: float, dof: int) -> float:
    """``P(X > x)`` for ``X`` chi-square with an even number ``dof`` of degrees of freedom:
    ``exp(-x/2) sum_{i < dof/2} (x/2)^i / i!`` (summed in logarithms: no underflow)."""
    if dof <= 0 or dof % 2:
        raise ValueError(f"dof must be even and positive, got {dof}")
    half = max(x, 0.0) / 2.0
    if half == 0.0:
        return 1.0
    logs = [-half + i * math.log(half) - math.lgamma(i + 1) for i in range(dof // 2)]
    top = max(logs)
    return min(1.0, math.exp(top) * math.fsum(math.exp(v - top) for v in logs))


def _word_splits(evidence: InlierSelection, state: bundle.RigState,
                 points_in_board: F64) -> None:
    """Why each view given a pose of its own left its instant: how far the board moved
    between its pose and that of the other views of its instant still in use (mm)."""
    obs = evidence.observations
    in_use = ~evidence.dropped
    row_of = {int(view): row for row, view in enumerate(evidence.order)}
    evidence.split = {}
    for view, origin in evidence.split_from.items():
        row = row_of[view]
        if not in_use[row]:
            continue
        partners = [r for r in np.flatnonzero(in_use) if r != row and (
            int(obs.instant[r]) == origin
            or evidence.split_from.get(int(evidence.order[r])) == origin)]
        own = state.reference_from_board(int(obs.instant[row]))
        mine = points_in_board @ own[:3, :3].T + own[:3, 3]
        moved = [float(np.linalg.norm(mine - (points_in_board @ other[:3, :3].T
                                               + other[:3, 3]), axis=1).max())
                 for r in partners
                 for other in (state.reference_from_board(int(obs.instant[r])),)]
        mm = 1000 * max(moved, default=0.0)
        evidence.split[view] = (
            f"not simultaneous: the board moved {mm:.{1 if mm >= 1 else 2}f} mm between the "
            f"{'two images' if len(partners) == 1 else 'images'}" if moved else
            "not simultaneous: no other view of its instant is used")


@dataclass
class _Trial:
    """The solve before the views left out as not the board were taken back in: kept only
    if those views still fit once solved with the others, every view used before is still
    used and the noise estimate grows by at most :data:`RETRY_SIGMA_GROWTH`."""

    state: bundle.RigState
    refinement: normal.Refinement
    sigma: float
    shift: F64
    inliers: B8
    rejected: dict[int, str]
    outlying: set[int]

    @classmethod
    def before(cls, state: bundle.RigState, refinement: normal.Refinement, sigma: float,
               shift: F64, evidence: InlierSelection) -> _Trial:
        return cls(state, refinement, sigma, shift, evidence.inliers.copy(),
                   dict(evidence.rejected), set(evidence.outlying))

    def holds(self, evidence: InlierSelection, state: bundle.RigState, sigma: float) -> bool:
        """Whether the solve with the views taken back in is kept."""
        used_before = [view for view in evidence.order.tolist() if view not in self.rejected]
        return bool(self.outlying - evidence.outlying) \
            and not any(view in evidence.rejected for view in used_before) \
            and sigma <= RETRY_SIGMA_GROWTH * self.sigma \
            and all(np.isfinite(i).all() for i in state.intrinsics)

    def undo(self, evidence: InlierSelection
             ) -> tuple[bundle.RigState, normal.Refinement, float, F64]:
        """Back to the solve before the trial; its state, refinement, sigma and shift."""
        evidence.inliers, evidence.rejected = self.inliers, self.rejected
        evidence.outlying = self.outlying
        return self.state, self.refinement, self.sigma, self.shift


def _retry_outlying(evidence: InlierSelection, state: bundle.RigState, obs: bundle.Observations,
                    points_in_board: F64, lenses: list[tuple[str, tuple[int, int]]]
                    ) -> tuple[bundle.RigState, int]:
    """Take the views left out as not the board back in (see the module's text), each posed
    afresh by PnP through the solution's lens ``(distortion model, image size)`` of its
    camera: the pose of its instant, or, when a view in use holds the instant, a pose of its
    own; a view whose corners that pose does not put in front of the camera stays out. The
    state to solve from, and how many views were taken back in."""
    state = state.copy()
    in_use = ~evidence.dropped
    restored = 0
    for row in np.flatnonzero(np.isin(evidence.order, list(evidence.outlying))):
        instant, camera = int(obs.instant[row]), int(obs.camera[row])
        ids = np.flatnonzero(obs.mask[row])
        distortion_model, size = lenses[camera]
        camera_from_board = board_pose(
            points_in_board[ids], obs.observed[row, ids],
            model_of(distortion_model, state.intrinsics[camera], size))
        if camera_from_board is None or np.any(
                points_in_board @ camera_from_board[2, :3] + camera_from_board[2, 3] <= 0):
            continue
        reference_from_board = np.linalg.inv(state.camera_from_reference(camera)) \
            @ camera_from_board
        if np.any(in_use & (obs.instant == instant)):
            state = evidence.split_off(int(row), state, reference_from_board)
        else:
            state.board_rotation[instant] = reference_from_board[:3, :3]
            state.board_translation[instant] = reference_from_board[:3, 3]
        evidence.restore(int(row))
        in_use[row] = True
        restored += 1
    return state, restored


def _weigh_blur(evidence: InlierSelection, norm: F64, speeds: F64) -> bool:
    """Fit the blur law to the views' residuals, weight them by it and leave out the views
    beyond its limit; whether there was blur to weigh."""
    inliers = evidence.inliers
    counts = inliers.sum(axis=1).astype(np.float64)
    # mean square per coordinate; a view's pose takes 6 of its 2n degrees of freedom
    mean_square = np.sum(np.where(inliers, norm, 0.0) ** 2, axis=1) \
        / np.maximum(2 * counts - 6, 1)
    blur = fit_blur(speeds, mean_square, counts)
    if blur is None:
        return False
    evidence.blur = blur
    evidence.observations.weight = evidence.observations.weight * blur.weight(speeds)
    for row in np.flatnonzero((speeds > blur.limit_px) & ~evidence.dropped):
        evidence.drop(int(row), f"motion blur: the board moved {speeds[row]:.1f} px/frame "
                      f"(limit {blur.limit_px:.1f})")
        evidence.blurred += 1
    return True


def _moved(obs: bundle.Observations, shift_px: F64) -> bundle.Observations:
    """The same observations moved by ``shift_px`` ``(V, N, 2)``."""
    return dataclasses.replace(obs, observed=obs.observed + shift_px)


def _residual_norms(state: bundle.RigState, layout: bundle.Layout, obs: bundle.Observations,
                    points_in_board: F64) -> F64:
    """Length ``(V, N)`` of every seen corner's unweighted residual (px)."""
    residual = bundle.linearize(state, layout, obs, points_in_board, jacobian=False).residuals
    return np.asarray(np.linalg.norm(residual, axis=2) / obs.weight[:, None])
