"""Calibrate N cameras jointly from every view: seed, refine robustly, test, report.

Each camera is seeded by OpenCV's calibration of a sample of its views, every view's board
pose by PnP and every rig transform by the consensus of the instants two cameras share; then
one least-squares problem (:mod:`.bundle`) refines every camera's intrinsics, the rig and
every board pose from every view, leaving out outlier corners and weighting blurred views
down (:mod:`.robust`). With ``tangential="auto"`` each camera's p1, p2 are then tested: the
problem is solved again without them, and they stay only when that raises the residual more
than noise would (a likelihood ratio, chi-square with 2 degrees of freedom). With
``board_warp="auto"`` the board's warp is then cross-validated (:mod:`.warp_choice`) and,
when chosen, the problem solved again with it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from . import bundle
from .lens import INTRINSIC_NAMES, model_of
from .motion import BlurModel
from .options import TANGENTIAL_P_VALUE, CalibrationOptions, TangentialTest
from .robust import (
    BoardView,
    BoardViews,
    InlierSelection,
    Problem,
    camera_views,
    robust_solve,
    threshold_sigma,
)
from .warp_choice import WarpChoice, choose_warp

__all__ = ["MIN_VIEWS", "BoardView", "JointResult", "Problem", "calibrate_cameras",
           "camera_views", "check_view_counts", "threshold_sigma"]

B8 = npt.NDArray[np.bool_]
MIN_VIEWS = 5


@dataclass
class JointResult:
    """Calibrated cameras, rig and board poses, with the evidence and what uncertainty needs.

    Cameras are numbered as the ``sizes`` given (every per-camera list follows it), views as
    the ``views`` given: ``residuals_px[i]`` ``(M, 2)`` (observed - projected) and
    ``inliers[i]`` ``(M,)`` follow the order of ``views[i]``'s corners; views in
    ``rejected`` carry no weight. Each of ``views`` is at the instant whose board pose it
    was solved with: a view in ``split`` left the instant it was given, whose other views
    saw the board elsewhere (not simultaneous), for a board pose of its own (a new instant
    number).
    """

    views: list[BoardView]
    models: list[CameraModel]
    options: list[CalibrationOptions]  # per camera, "auto" tangential resolved
    tangential_tests: list[TangentialTest | None]
    camera_from_reference: list[F64]  # (4, 4) per camera
    reference_from_board: dict[int, F64]  # instant -> (4, 4)
    sigma_px: float  # noise per coordinate of a still board's corners, from the residuals
    residuals_px: list[F64]
    inliers: list[B8]
    rejected: dict[int, str]  # view index -> why it carries no weight
    std: list[dict[str, float]]  # per camera, every intrinsic (0 when held)
    #: per camera, covariance (6, 6) of its rig transform: rotation increment (rad, R <-
    #: exp([d]x) R), then translation (m); zero for the reference
    rig_covariance: list[F64]
    problem: Problem
    blur: BlurModel | None = None
    blurred_views: int = 0
    rounds: int = 0
    warp_choice: WarpChoice | None = None  # the warp's cross-validation (board_warp "auto")
    split: dict[int, str] = field(default_factory=dict)  # view index -> why
    #: per camera, the model fitted with the terms its tangential test left out (p1 p2), when
    #: it left them out (or the k1 k2 k3 fit, :func:`~.beyond.k3_beyond_the_views`): how far
    #: the chosen model's projections are from it is part of their uncertainty (the covariance
    #: of a model cannot see a term it does not have)
    left_out_models: list[CameraModel | None] = field(default_factory=list)

    @property
    def board_warp_m(self) -> tuple[F64, F64] | None:
        """The board's warp ``(wx, wy)`` (m, :mod:`.warp`) and its standard deviations, when
        estimated (None: held flat)."""
        columns = self.problem.layout.warp_columns
        if not len(columns):
            return None
        covariance = self.problem.global_covariance()[np.ix_(columns, columns)]
        return (self.problem.state.board_warp_m.copy(),
                np.sqrt(np.maximum(np.diag(covariance), 0.0)))

    @property
    def rms_px(self) -> float:
        """RMS reprojection error (px, 2-D) over the inlier corners."""
        squared = [np.sum(r[m] ** 2) for r, m in zip(self.residuals_px, self.inliers,
                                                      strict=True)]
        count = sum(int(m.sum()) for m in self.inliers)
        return math.sqrt(float(sum(squared)) / max(count, 1))

    def used_views(self, camera: int) -> list[int]:
        """The views of one camera that carry weight, in view order."""
        return [i for i in camera_views(self.views, camera) if i not in self.rejected]

    def parameters(self, camera: int) -> dict[str, float]:
        """One camera's intrinsics by name (fx, fy, cx, cy, then the distortion
        coefficients); their standard deviations are ``std[camera]``."""
        m = self.models[camera]
        names = ["fx", "fy", "cx", "cy", *INTRINSIC_NAMES[m.distortion_model][4:]]
        return dict(zip(names, [m.fx, m.fy, m.cx, m.cy, *m.d.tolist()], strict=True))

    def camera_from_board(self, view: int) -> F64:
        """The board's pose ``(4, 4)`` in the camera of one view."""
        board_view = self.views[view]
        return self.camera_from_reference[board_view.camera] \
            @ self.reference_from_board[board_view.instant]

    def view_rms_px(self, view: int) -> float:
        """RMS error of one view's inlier corners (px)."""
        residual = self.residuals_px[view][self.inliers[view]]
        return math.sqrt(float(np.mean(np.sum(residual ** 2, axis=1)))) if len(residual) \
            else float("nan")

    def centres_px(self, view: int) -> F64:
        """Corners ``(M, 2)`` of one view as the solver fitted them: a circle grid's
        detections moved by the disc shift at the solution onto the circles' centres (the
        detections themselves for other boards)."""
        row = int(np.flatnonzero(self.problem.order == view)[0])
        return np.asarray(self.problem.observations.observed[row, self.views[view].point_ids])

    @property
    def outlier_corners(self) -> int:
        """Corners of used views left out as outliers."""
        return sum(int((~m).sum()) for i, m in enumerate(self.inliers) if i not in self.rejected)


def check_view_counts(views: list[BoardView], cameras: int) -> None:
    """Every one of ``cameras`` has at least :data:`MIN_VIEWS` views (ProcessorError
    otherwise)."""
    for camera in range(cameras):
        count = len(camera_views(views, camera))
        if count < MIN_VIEWS:
            raise ProcessorError(
                f"too few good views to calibrate{'' if cameras == 1 else f' camera {camera}'}: "
                f"{count} (need at least {MIN_VIEWS}); record more board poses")


def calibrate_cameras(points_in_board: F64, views: list[BoardView],
                      sizes: list[tuple[int, int]],
                      options: CalibrationOptions | list[CalibrationOptions], *,
                      seeds: list[CameraModel] | None = None,
                      reject_outliers: bool = True,
                      disc_diameter_m: float | None = None) -> JointResult:
    """Calibrate cameras ``0 .. len(sizes) - 1`` from ``views`` of the board points
    ``points_in_board`` ``(N, 3)``; camera 0 is the rig's reference. ``options`` apply to
    every camera, or one each; ``seeds`` (one model per camera) replace OpenCV's seed
    calibration; without ``reject_outliers`` every corner counts. With ``disc_diameter_m``
    the points are the centres of circles that diameter across, seen as the centroids of
    their images (see :mod:`.discs`). The first camera's ``board_warp`` says whether the
    board's warp is estimated (the board is shared)."""
    cameras = len(sizes)
    wanted = options if isinstance(options, list) else [options] * cameras
    check_view_counts(views, cameras)
    data = BoardViews(points_in_board, views, sizes, disc_diameter_m)
    auto = [o.tangential == "auto" and o.has_tangential for o in wanted]
    final = [o.with_tangential("estimate") if a else o for o, a in zip(wanted, auto, strict=True)]
    warp = wanted[0].board_warp == "on"
    problem, evidence, rounds = robust_solve(data, final, seeds=seeds, reject=reject_outliers,
                                             warp=warp)
    tests: list[TangentialTest | None] = [None] * cameras
    trials: dict[int, tuple[Problem, int]] = {}
    for camera in (c for c in range(cameras) if auto[c]):
        trial = list(final)
        trial[camera] = wanted[camera].with_tangential("zero")
        without, _e, trial_rounds = robust_solve(
            data, trial, state=_without_tangential(problem.state, camera), evidence=evidence,
            warp=warp)
        trials[camera] = without, trial_rounds
        chi2 = (without.cost - problem.cost) / problem.sigma_px ** 2
        tests[camera] = TangentialTest(chi2, math.exp(-max(chi2, 0.0) / 2) < TANGENTIAL_P_VALUE)
    dropped = [c for c, t in enumerate(tests) if t is not None and not t.estimated]
    left_out = [_model(problem, c) if c in dropped else None for c in range(cameras)]
    for camera in dropped:
        final[camera] = wanted[camera].with_tangential("zero")
    if len(dropped) == 1:  # the trial without that camera's p1, p2 is the solve wanted
        problem, more = trials[dropped[0]]
        rounds += more
    elif dropped:
        state = problem.state
        for camera in dropped:
            state = _without_tangential(state, camera)
        problem, _e, more = robust_solve(data, final, state=state, evidence=evidence,
                                         warp=warp)
        rounds += more
    choice = choose_warp(problem) if wanted[0].board_warp == "auto" else None
    if choice is not None and choice.chosen:
        warp = True
        problem, _e, more = robust_solve(data, final, state=problem.state, evidence=evidence,
                                         warp=True)
        rounds += more
    final = [dataclasses.replace(o, board_warp="on" if warp else "off") for o in final]
    result = _result(problem, views, evidence, options=final, tests=tests, rounds=rounds,
                     warp_choice=choice)
    result.left_out_models = left_out
    return result


def _model(problem: Problem, camera: int) -> CameraModel:
    """One camera's model in ``problem``'s state."""
    setup = problem.layout.setups[camera]
    return model_of(setup.distortion_model, problem.state.intrinsics[camera], setup.size)


def _without_tangential(state: bundle.RigState, camera: int) -> bundle.RigState:
    """``state`` with p1 = p2 = 0 for one camera (plumb_bob order: fx fy cx cy k1 k2 p1 p2)."""
    out = state.copy()
    out.intrinsics[camera][6:8] = 0.0
    return out


def _result(problem: Problem, views: list[BoardView], evidence: InlierSelection, *,
            options: list[CalibrationOptions], tests: list[TangentialTest | None],
            rounds: int, warp_choice: WarpChoice | None) -> JointResult:
    state, layout, obs = problem.state, problem.layout, problem.observations
    models = [model_of(s.distortion_model, i, s.size)
              for s, i in zip(layout.setups, state.intrinsics, strict=True)]
    residual = bundle.linearize(state, layout, obs.with_mask(np.ones_like(obs.mask)),
                                problem.points_in_board, jacobian=False).residuals
    residual = residual / obs.weight[:, None, None]
    residuals, inliers = [np.zeros((0, 2))] * len(views), [np.zeros(0, bool)] * len(views)
    for row, view in enumerate(problem.order):
        ids = views[view].point_ids
        residuals[view] = -residual[row, ids]
        inliers[view] = evidence.inliers[row, ids]
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
    solved = list(views)
    for row, view in enumerate(problem.order):
        instant = int(problem.instants[obs.instant[row]])
        if instant != views[view].instant:
            solved[view] = dataclasses.replace(views[view], instant=instant)
    return JointResult(
        views=solved, models=models, options=options, tangential_tests=tests,
        camera_from_reference=[state.camera_from_reference(c) for c in range(len(models))],
        reference_from_board={int(problem.instants[p]): state.reference_from_board(p)
                              for p in range(len(problem.instants))},
        sigma_px=problem.sigma_px, residuals_px=residuals, inliers=inliers,
        rejected=dict(evidence.rejected), std=std, rig_covariance=rig_covariance,
        problem=problem, blur=evidence.blur, blurred_views=evidence.blurred, rounds=rounds,
        warp_choice=warp_choice, split=dict(evidence.split))
