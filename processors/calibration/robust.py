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
the solve before the trial stands. Views of a moving board carry their speed; after the
first solve the blur law of :mod:`.motion` is fitted to their residuals, weights them and
leaves out views too blurred to help. The centres of a circle grid's circles are measured as
the centroids of their images; each round moves them by the shift :mod:`.discs` computes at
the current solution, until the shift settles.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from . import bundle, normal
from .discs import centroid_shifts
from .lens import model_of
from .motion import BlurModel, fit_blur
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

    def global_covariance(self) -> F64:
        """Covariance ``(G, G)`` of the global unknowns (intrinsics, rig), board poses
        eliminated: their coupling is included."""
        return self.sigma_px ** 2 * self.normal.global_covariance()

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
    layout = bundle.Layout.of(setups, state, warp=warp)

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
    rounds, trial = 0, None
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
        if rounds >= MAX_ROUNDS * (1 if trial is None else 2):
            break
        if not (fresh and reject):
            if settled:
                break
            continue
        if rounds == 1 and np.any(speeds > 0) and _weigh_blur(evidence, norm, speeds):
            continue
        if not _reject_outliers(evidence, norm, sigma) and settled:
            if trial is not None or not evidence.outlying:
                break
            trial = _Trial.before(state, refinement, sigma, shift, evidence)
            state, restored = _retry_outlying(evidence, state, _moved(obs, shift),
                                              points_in_board,
                                              [(o.distortion_model, s) for o, s in
                                               zip(options, sizes, strict=True)])
            if not restored:
                trial = None
                break
    if trial is not None and not trial.holds(evidence, state, sigma):
        state, refinement, sigma, shift = trial.undo(evidence)
    problem = Problem(state, layout, _moved(obs, shift).with_mask(evidence.inliers),
                      refinement.normal, points_in_board, sigma, evidence.instants,
                      evidence.order)
    return problem, evidence, rounds


def _sigma(weighted_norm: F64, inliers: B8, layout: bundle.Layout) -> float:
    """Noise per coordinate at unit weight, from the inlier residuals (dof corrected)."""
    count = int(inliers.sum())
    dof = max(2 * count - layout.global_count - 6 * int(inliers.any(axis=1).sum()), 1)
    return math.sqrt(float(np.sum(weighted_norm[inliers] ** 2)) / dof)


def _reject_outliers(evidence: InlierSelection, norm: F64, sigma: float) -> bool:
    """Mark the corners beyond the threshold (and views that lose most of theirs); whether
    anything changed."""
    obs, seen = evidence.observations, evidence.observations.mask
    dropped = evidence.dropped
    limit = threshold_sigma(int(evidence.inliers.sum())) * sigma / obs.weight[:, None]
    new = seen & (norm <= limit) & ~dropped[:, None]
    lost = ((seen & ~new).sum(axis=1) > VIEW_OUTLIER_SHARE * seen.sum(axis=1)) \
        | (new.sum(axis=1) < MIN_VIEW_POINTS)
    lost &= ~dropped
    changed = not np.array_equal(new, evidence.inliers) or bool(lost.any())
    evidence.inliers = new
    for row in np.flatnonzero(lost):
        evidence.drop(int(row), f"{int((seen[row] & ~new[row]).sum())} of "
                      f"{int(seen[row].sum())} corners beyond the outlier threshold: not the "
                      "board at one pose")
        evidence.outlying.add(int(evidence.order[row]))
    return changed


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
    """Take the views left out as not the board back in (see the module's text); a board
    pose that no view in use holds is found afresh by PnP through the solution's lens
    ``(distortion model, image size)`` of the view's camera, and a view whose corners that
    pose does not put in front of the camera stays out. The state to solve from, and how
    many views were taken back in."""
    state = state.copy()
    in_use = ~evidence.dropped
    restored = 0
    for row in np.flatnonzero(np.isin(evidence.order, list(evidence.outlying))):
        instant, camera = int(obs.instant[row]), int(obs.camera[row])
        if not np.any(in_use & (obs.instant == instant)):
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
