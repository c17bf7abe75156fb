"""Solving: every camera, the rig and every board pose from the detected views, at once.

Every view of every camera goes into one least-squares problem
(:func:`processors.calibration.joint.calibrate_cameras`): intrinsics of all cameras, the rig
and every board pose, outlier corners left out, blurred views weighted down; a circle grid's
circles are modelled as discs of the diameter given or measured in the views (their
detections are the centroids of the discs' images). The solvers know nothing of frames;
here their views are mapped back to frame indices, a view being named by its first frame,
which is what every later step (summary, evidence, report) speaks.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field

import numpy as np

from processors.calibration.board import Board
from processors.calibration.holds import Seen
from processors.calibration.joint import (
    BoardView,
    JointResult,
    calibrate_cameras,
    camera_views,
    check_view_counts,
)
from processors.calibration.model_order import OrderChoice, choose_orders
from processors.calibration.mono import MonoResult, mono_camera_info
from processors.calibration.options import CalibrationOptions
from processors.calibration.robust import seed_camera
from processors.calibration.selection import Coverage, coverage, view_parameters
from processors.calibration.stereo import StereoResult, orient_right_views, stereo_result
from processors.calibration.targets import guides_charuco
from processors.calibration.uncertainty import UncertaintyMap
from processors.calibration.validation import CrossValidation
from processors.errors import ProcessorError
from replay.camera import CameraModel
from replay.messages import F64, CameraInfo
from replay.records import ScenarioCamera

from ..errors import CalibrationError
from .circles import CircleSize, circle_size
from .instants import ViewsOfRig, rig_views
from .rig_pairs import PairSolution, rig_pairs
from .statistics import CameraStatistics, camera_statistics
from .views import CameraViews, DetectedFrame

__all__ = ["CalibratedCamera", "CameraSolution", "RigSolution", "StereoSolution",
           "calibrated_cameras", "solve_rig"]


@dataclass(frozen=True)
class CameraSolution:
    """One camera of the joint calibration. ``result``'s view ids are frame indices: each
    view is named by its first frame; ``view_of`` maps every frame of a view to that name."""

    views: CameraViews
    candidates: list[int]  # frames whose board passed every check
    selected: list[int]  # frames in the views given to the solver (all the candidates)
    result: MonoResult
    view_of: dict[int, int]
    frames_in_view: dict[int, int]  # view name -> how many frames it averages
    coverage: Coverage  # of the used views
    statistics: Future[CameraStatistics]  # computed beside the evidence pass (solve_rig)
    order: OrderChoice | None = None  # the radial order's cross-validation, when chosen

    @property
    def uncertainty(self) -> UncertaintyMap:
        """Projection uncertainty at the working range (waits for the statistics)."""
        return self.statistics.result().uncertainty

    @property
    def rays_uncertainty(self) -> UncertaintyMap:
        """Projection uncertainty of points far away (waits for the statistics)."""
        return self.statistics.result().rays_uncertainty

    @property
    def cross_validation(self) -> CrossValidation | None:
        """The halves' cross-validation (waits for the statistics)."""
        return self.statistics.result().cross_validation

    @property
    def cross_validation_px(self) -> float | None:
        """Expected worst error of the calibration (rays) from the halves' cross-validation."""
        return None if self.cross_validation is None else self.cross_validation.worst_px

    def used_corners(self) -> list[F64]:
        """Corners ``(M, 2)`` of every used view (its first frame's), in view order."""
        return [self.views.corners(i) for i in self.result.view_ids]

    def rejected_corners(self) -> list[F64]:
        """Corners of every distinct frame whose board was found but not used."""
        return [f.detection.corners_px for f in self.views.distinct()
                if f.detection is not None and self.rejection(f) is not None]

    def rejection(self, frame: DetectedFrame) -> str | None:
        """Why a frame's board is not (in) a view (None: it is)."""
        if frame.detection is not None and not frame.detection.accepted:
            return frame.detection.reason
        if frame.reason:
            return frame.reason
        return self.result.rejected.get(self.view_of.get(frame.index, -1))

    def outlier_limit_px(self) -> float | None:
        """Views are not judged by their RMS: outliers are single corners."""
        return None

    def status(self, frame: DetectedFrame) -> tuple[str, bool]:
        """Text drawn on an annotated frame, and whether the view was used."""
        if frame.detection is None:
            return "no board found", False
        why = self.rejection(frame)
        if why is not None:
            return f"rejected: {why}", False
        name = self.view_of.get(frame.index)
        if name is not None and name in self.result.view_rms_px:
            held = self.frames_in_view[name]
            suffix = f", held pose of {held} frames" if held > 1 else ""
            return f"used: RMS {self.result.view_rms_px[name]:.3f} px{suffix}", True
        return "not used", False


@dataclass(frozen=True)
class StereoSolution:
    """The rig's rectification and figures, and the joint views (left frame, right frame,
    each named by its first frame) it used or left out."""

    result: StereoResult
    pairs: list[tuple[int, int]]
    rejected: list[tuple[tuple[int, int], str]]


@dataclass(frozen=True)
class RigSolution:
    """Everything the joint solve found."""

    cameras: list[CameraSolution]
    stereo: StereoSolution | None
    joint: JointResult
    rig: ViewsOfRig
    circles: CircleSize | None = None
    measured_again: list[str] | None = None  # per camera: what the second measurement did
    pairs: list[PairSolution] = field(default_factory=list)  # a rig's pairs (not stereo)


def measured_again_text(before: ViewsOfRig, after: ViewsOfRig, first: JointResult,
                        final: JointResult, camera: int) -> str:
    """One camera's second measurement in words: how many of its used corners moved, by how
    much, and the corner noise before and after."""
    shifts = [np.linalg.norm(before.views[i].corners_px - after.views[i].corners_px, axis=1)
              for i in camera_views(before.views, camera) if i not in first.rejected]
    moved = np.concatenate(shifts) if shifts else np.zeros(0)
    changed = moved[moved > 0]
    median = f", by {np.median(changed):.3f} px (median)" if len(changed) else ""
    return (f"on the board plane through the first solve: {len(changed)} of {len(moved)} "
            f"corners moved{median}; corner noise {first.sigma_px:.3f} → "
            f"{final.sigma_px:.3f} px per coordinate")


def _mono_result(joint: JointResult, rig: ViewsOfRig, camera: int) -> MonoResult:
    """One camera's share of the joint result, its views named by their first frames."""
    mine = camera_views(rig.views, camera)
    name = {i: rig.frames_of[i][0] for i in mine}
    used = [i for i in mine if i not in joint.rejected]
    camera_from_reference = joint.camera_from_reference[camera]
    return MonoResult(
        model=joint.models[camera], rms_px=joint.rms_px,
        view_ids=[name[i] for i in used],
        view_rms_px={name[i]: joint.view_rms_px(i) for i in used},
        rejected={name[i]: joint.rejected[i] for i in mine if i in joint.rejected},
        std=dict(joint.std[camera]),
        camera_from_board={name[i]: camera_from_reference
                           @ joint.reference_from_board[rig.views[i].instant] for i in used},
        residuals_px={name[i]: joint.residuals_px[i] for i in used},
        inliers={name[i]: joint.inliers[i] for i in used},
        options=joint.options[camera], tangential_test=joint.tangential_tests[camera],
        sigma_px=joint.sigma_px, joint=joint)


def _seeds(rig: ViewsOfRig, board: Board, sizes: list[tuple[int, int]],
           options: CalibrationOptions) -> list[CameraModel]:
    try:
        check_view_counts(rig.views, len(sizes))
    except ProcessorError as err:
        raise CalibrationError(str(err)) from None
    return [seed_camera(board.points_in_board(), rig.views, camera, size, options)
            for camera, size in enumerate(sizes)]


def _seen(view: BoardView) -> Seen:
    return Seen(view.point_ids, view.corners_px)


def _chain(at: list[dict[int, int]]) -> list[int]:
    """The cameras in the order they link to camera 0 through the instants ``at`` (camera ->
    view) they share: camera 0, the cameras sharing an instant with it, then theirs."""
    order = [0]
    while more := sorted({c for cameras in at if cameras.keys() & set(order)
                          for c in cameras} - set(order)):
        order += more
    return order


def _oriented(rig: ViewsOfRig, board: Board, seeds: list[CameraModel]) -> ViewsOfRig:
    """Every camera's views numbered from the same end of a symmetric board as those of a
    camera it shares the instant with (camera 0 first, then along the chain; for a stereo
    pair, the right views as the left ones)."""
    if not board.symmetric:
        return rig
    at: dict[int, dict[int, int]] = {}  # instant -> camera -> view
    for index, view in enumerate(rig.views):
        at.setdefault(view.instant, {})[view.camera] = index
    order = _chain(list(at.values()))
    points = board.points_in_board()
    views = list(rig.views)
    for position, camera in enumerate(order[1:], start=1):
        by_partner: dict[int, list[tuple[int, int]]] = {}
        for cameras in at.values():
            partner = next((c for c in order[:position] if c in cameras), None)
            if camera in cameras and partner is not None:
                by_partner.setdefault(partner, []).append((cameras[partner], cameras[camera]))
        for partner, pairs in by_partner.items():
            turned = orient_right_views(points, [_seen(views[pv]) for pv, _ in pairs],
                                        [_seen(views[cv]) for _, cv in pairs],
                                        left_model=seeds[partner], right_model=seeds[camera])
            for (_, cv), seen in zip(pairs, turned, strict=True):
                views[cv] = BoardView(views[cv].camera, views[cv].instant, seen.point_ids,
                                      seen.corners_px, speed_px=views[cv].speed_px)
    return ViewsOfRig(views, rig.frames_of, rig.pairs, rig.candidates, rig.frame_scatter_px)


def _prepared(cameras: list[CameraViews], board: Board, options: CalibrationOptions, *,
              approximate_s: float | None, stereo_note: bool
              ) -> tuple[ViewsOfRig, list[CameraModel], list[tuple[int, int]]]:
    """The rig's views (right views oriented as the left ones), the seed models and the
    image sizes."""
    sizes = [c.size for c in cameras]
    rig = rig_views(cameras, board, approximate_s=approximate_s, stereo_note=stereo_note)
    seeds = _seeds(rig, board, sizes, options)
    return _oriented(rig, board, seeds), seeds, sizes


def guiding_models(cameras: list[CameraViews], board: Board, options: CalibrationOptions, *,
                   approximate_s: float | None) -> dict[str, CameraModel]:
    """A first calibration's models, by namespace, to guide a second ChArUco detection; none
    when the lens model cannot (:func:`~processors.calibration.targets.guides_charuco`)."""
    if not guides_charuco(options.distortion_model):
        return {}
    rig, seeds, sizes = _prepared(cameras, board, options, approximate_s=approximate_s,
                                  stereo_note=False)
    joint = calibrate_cameras(board.points_in_board(), rig.views, sizes,
                              dataclasses.replace(options, board_warp="off"), seeds=seeds)
    return {views.source.namespace: model
            for views, model in zip(cameras, joint.models, strict=True)}


def solve_rig(cameras: list[CameraViews], board: Board, options: CalibrationOptions, *,
              approximate_s: float | None, diameter_m: float | None = None,
              background: bool = False,
              remeasure: Callable[[ViewsOfRig, JointResult], ViewsOfRig] | None = None,
              as_rig: bool = False) -> RigSolution:
    """Calibrate every camera, and for two the stereo rig (with ``as_rig``, or for three or
    more cameras: every pair of the rig), from every view; a circle grid's
    circles are ``diameter_m`` across, or as the views measure them; with ``choose_order``
    options each camera's radial order is chosen first, by cross-validation over its views
    (:mod:`processors.calibration.model_order`), and with ``board_warp="auto"`` the board's
    warp after the flat solve (:mod:`processors.calibration.warp_choice`; the guiding
    models of a ChArUco detection are solved flat). ``remeasure`` gives the
    views measured again through a first solution (:mod:`.remeasure`), which are then solved
    again from it. With ``background`` the cameras' :class:`~.statistics.CameraStatistics`
    (most of the work) of a short log are computed on a thread of their own while the caller
    goes on (see :func:`~.statistics.camera_statistics`); reading them waits, and raises
    their error."""
    circles = circle_size(cameras, board, diameter_m)
    disc_diameter_m = circles.diameter_m if circles is not None else None
    rig, seeds, sizes = _prepared(cameras, board, options, approximate_s=approximate_s,
                                  stereo_note=len(cameras) > 1)
    points = board.points_in_board()
    orders = choose_orders(points, rig.views, sizes, options)
    chosen = [options if o is None else o.options for o in orders]
    seeds = [s if o.distortion_model == options.distortion_model
             else seed_camera(points, rig.views, camera, sizes[camera], o)
             for camera, (s, o) in enumerate(zip(seeds, chosen, strict=True))]
    joint = calibrate_cameras(points, rig.views, sizes, chosen, seeds=seeds,
                              disc_diameter_m=disc_diameter_m)
    again = None
    if remeasure is not None:
        first, before = joint, rig
        rig = remeasure(rig, joint)
        joint = calibrate_cameras(points, rig.views, sizes, chosen, seeds=joint.models,
                                  disc_diameter_m=disc_diameter_m)
        again = [measured_again_text(before, rig, first, joint, c) for c in range(len(cameras))]
    statistics = camera_statistics(joint, rig.views, points, sizes,
                                   disc_diameter_m=disc_diameter_m, background=background)
    solutions = []
    for index, views in enumerate(cameras):
        result = _mono_result(joint, rig, index)
        mine = camera_views(rig.views, index)
        view_of = {f: rig.frames_of[i][0] for i in mine for f in rig.frames_of[i]}
        used = [(rig.views[i].corners_px, rig.views[i].point_ids) for i in mine
                if i not in joint.rejected]
        params = np.array([view_parameters(c, board, views.size, ids) for c, ids in used])
        solutions.append(CameraSolution(
            views, rig.candidates[index], sorted(view_of), result, view_of,
            {rig.frames_of[i][0]: len(rig.frames_of[i]) for i in mine},
            coverage(params, [c for c, _ in used], views.size),
            statistics[index], orders[index]))
    stereo, pairs = None, []
    if as_rig or len(cameras) > 2:
        pairs = rig_pairs(joint, rig, points_in_board=points, square_m=board.square_m)
    elif len(cameras) == 2:
        rectified = stereo_result(joint, rig.pairs, points_in_board=points,
                                  square_m=board.square_m)
        names = [(rig.frames_of[lv][0], rig.frames_of[rv][0]) for lv, rv in rig.pairs]
        stereo = StereoSolution(rectified, [names[i] for i in rectified.view_ids],
                                [(names[i], why) for i, why in
                                 sorted(rectified.rejected.items())])
    return RigSolution(solutions, stereo, joint, rig, circles, again, pairs)


@dataclass(frozen=True)
class CalibratedCamera:
    """A solved camera with the model to publish and, in simulated logs, its truth."""

    solution: CameraSolution
    camera_info: CameraInfo
    truth: ScenarioCamera | None

    @property
    def views(self) -> CameraViews:
        """The camera's views."""
        return self.solution.views


def calibrated_cameras(solutions: list[CameraSolution], stereo: StereoSolution | None,
                       truth: list[ScenarioCamera | None]) -> list[CalibratedCamera]:
    """Each camera's calibrated model: mono with camera_calibration's P; stereo with the
    rectification (R, P) of the rig."""
    out = []
    for index, (solution, camera_truth) in enumerate(zip(solutions, truth, strict=True)):
        m, frame_id = solution.result.model, solution.views.frame_id
        if stereo is None:
            info = mono_camera_info(m, frame_id)
        else:
            r, p = (stereo.result.r1, stereo.result.p1) if index == 0 else \
                (stereo.result.r2, stereo.result.p2)
            info = CameraInfo(0, frame_id, m.width, m.height, m.distortion_model, m.d, m.k,
                              r, p)
        out.append(CalibratedCamera(solution, info, camera_truth))
    return out
