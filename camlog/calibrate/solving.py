"""Solving: every camera, the rig and every board pose from the detected views, at once.

Every view of every camera goes into one least-squares problem
(:func:`processors.calibration.joint.calibrate_cameras`): intrinsics of all cameras, the rig
and every board pose, outlier corners left out, blurred views weighted down; a circle grid's
circles are modelled as discs of the diameter given or measured in the views (their
detections are the centroids of the discs' images). The solvers know nothing of frames: a
view is numbered by its index in the rig's views (:class:`~.instants.ViewsOfRig`), in the
solver as in every later step (summary, evidence, report), and its frames are
``rig.frames_of[view]``. The result is a :class:`RigSolution`: one :class:`CalibratedCamera`
per camera, the joint solve (the rig, every board pose) and the views.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from processors.calibration.beyond import k3_beyond_the_views
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
from processors.calibration.mono import mono_camera_info
from processors.calibration.options import CalibrationOptions
from processors.calibration.robust import seed_camera
from processors.calibration.selection import Coverage, coverage, view_parameters
from processors.calibration.stereo import StereoResult, orient_right_views, stereo_result
from processors.calibration.targets import guides_charuco
from processors.errors import ProcessorError
from replay.camera import CameraModel
from replay.messages import F64, CameraInfo
from replay.records import ScenarioCamera

from ..errors import CalibrationError
from .circles import CircleSize, circle_size
from .instants import ViewsOfRig, rig_views
from .offsets import CameraOffset
from .rig_pairs import PairSolution, rig_pairs
from .views import CameraViews, DetectedFrame

__all__ = ["CalibratedCamera", "RigSolution", "guiding_models", "solve_rig"]


@dataclass(frozen=True)
class CalibratedCamera:
    """One calibrated camera: its frames and detections, the model solved and the
    camera_info to publish (mono: camera_calibration's P; stereo: the rectification), its
    views in the rig's numbering and, in simulated logs, its truth."""

    index: int  # the camera's number in the joint solve (0: the rig's reference)
    views: CameraViews
    model: CameraModel
    camera_info: CameraInfo
    view_ids: list[int]  # its views (indices into the rig's views), in view order
    view_of: dict[int, int]  # frame index -> the view it is in
    coverage: Coverage  # of the used views
    order: OrderChoice | None = None  # the radial order's cross-validation, when chosen
    truth: ScenarioCamera | None = None


@dataclass(frozen=True)
class RigSolution:
    """Everything the joint solve found: the cameras, the joint result (the rig and every
    board pose; per view its residuals, inliers or why it was left out) and the views it
    solved, numbered as ``rig.views``; for two cameras the stereo rectification
    (``stereo.pairs``: the joint views used), for a rig every pair of cameras."""

    cameras: list[CalibratedCamera]
    joint: JointResult
    rig: ViewsOfRig
    stereo: StereoResult | None = None
    pairs: list[PairSolution] = field(default_factory=list)  # a rig's pairs (not stereo)
    circles: CircleSize | None = None
    measured_again: list[str] | None = None  # per camera: what the second measurement did
    offsets: list[CameraOffset] = field(default_factory=list)  # cameras 1..N-1 against 0

    def first_frame(self, view: int) -> int:
        """The frame a view is shown at: its first (a held pose spans several)."""
        return self.rig.frames_of[view][0]

    def used_views(self, camera: CalibratedCamera) -> list[int]:
        """A camera's views that carry weight, in view order."""
        return self.joint.used_views(camera.index)

    def used_corners(self, camera: CalibratedCamera) -> list[F64]:
        """Detected corners ``(M, 2)`` of every used view (at its first frame), in view
        order."""
        return [camera.views.corners(self.first_frame(v)) for v in self.used_views(camera)]

    def rejected_corners(self, camera: CalibratedCamera) -> list[F64]:
        """Corners of every distinct frame whose board was found but not used."""
        return [f.detection.corners_px for f in camera.views.distinct()
                if f.detection is not None and self.rejection(camera, f) is not None]

    def rejection(self, camera: CalibratedCamera, frame: DetectedFrame) -> str | None:
        """Why a frame's board is not (in) a used view (None: it is)."""
        if frame.detection is not None and not frame.detection.accepted:
            return frame.detection.reason
        if frame.reason:
            return frame.reason
        view = camera.view_of.get(frame.index)
        return None if view is None else self.joint.rejected.get(view)

    def status(self, camera: CalibratedCamera, frame: DetectedFrame) -> tuple[str, bool]:
        """Text drawn on an annotated frame, and whether its view was used."""
        if frame.detection is None:
            return "no board found", False
        why = self.rejection(camera, frame)
        if why is not None:
            return f"rejected: {why}", False
        view = camera.view_of.get(frame.index)
        if view is not None:
            held = len(self.rig.frames_of[view])
            suffix = f", held pose of {held} frames" if held > 1 else ""
            return f"used: RMS {self.joint.view_rms_px(view):.3f} px{suffix}", True
        return "not used", False


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
              approximate_s: float | None, stereo_note: bool,
              offsets: list[CameraOffset] | None = None
              ) -> tuple[ViewsOfRig, list[CameraModel], list[tuple[int, int]]]:
    """The rig's views (right views oriented as the left ones; cameras with an offset
    paired by it), the seed models and the image sizes."""
    sizes = [c.size for c in cameras]
    offsets_ns = None if not offsets else [None, *(o.offset_ns for o in offsets)]
    rig = rig_views(cameras, board, approximate_s=approximate_s, stereo_note=stereo_note,
                    offsets_ns=offsets_ns)
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


def _camera_info(model: CameraModel, frame_id: str, stereo: StereoResult | None,
                 index: int) -> CameraInfo:
    """A camera's calibrated camera_info: mono with camera_calibration's P; stereo with the
    rectification (R, P) of the rig."""
    if stereo is None:
        return mono_camera_info(model, frame_id)
    r, p = (stereo.r1, stereo.p1) if index == 0 else (stereo.r2, stereo.p2)
    return CameraInfo(0, frame_id, model.width, model.height, model.distortion_model,
                      model.d, model.k, r, p)


def solve_rig(cameras: list[CameraViews], board: Board, options: CalibrationOptions, *,
              approximate_s: float | None, diameter_m: float | None = None,
              remeasure: Callable[[ViewsOfRig, JointResult], ViewsOfRig] | None = None,
              as_rig: bool = False,
              truth: list[ScenarioCamera | None] | None = None,
              offsets: list[CameraOffset] | None = None) -> RigSolution:
    """Calibrate every camera, and for two the stereo rig (with ``as_rig``, or for three or
    more cameras: every pair of the rig), from every view; a circle grid's
    circles are ``diameter_m`` across, or as the views measure them; with ``choose_order``
    options each camera's radial order is chosen first, by cross-validation over its views
    (:mod:`processors.calibration.model_order`), and with ``board_warp="auto"`` the board's
    warp after the flat solve (:mod:`processors.calibration.warp_choice`; the guiding
    models of a ChArUco detection are solved flat). ``remeasure`` gives the
    views measured again through a first solution (:mod:`.remeasure`), which are then solved
    again from it. ``truth``: each camera's simulator record, when the log has one.
    ``offsets``: cameras 1..N-1's time offsets against camera 0 (:mod:`.offsets`), by which
    the views of those applied are paired."""
    circles = circle_size(cameras, board, diameter_m)
    disc_diameter_m = circles.diameter_m if circles is not None else None
    rig, seeds, sizes = _prepared(cameras, board, options, approximate_s=approximate_s,
                                  stereo_note=len(cameras) > 1, offsets=offsets)
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
    orders, chosen, joint = k3_beyond_the_views(points, rig.views, sizes, wanted=chosen,
                                                orders=orders, joint=joint,
                                                disc_diameter_m=disc_diameter_m)
    stereo, pairs = None, []
    if as_rig or len(cameras) > 2:
        pairs = rig_pairs(joint, rig, points_in_board=points, square_m=board.square_m)
    elif len(cameras) == 2:
        stereo = stereo_result(joint, rig.pairs, points_in_board=points,
                               square_m=board.square_m)
    solved = []
    for index, views in enumerate(cameras):
        mine = camera_views(rig.views, index)
        used = [rig.views[i] for i in joint.used_views(index)]
        params = np.array([view_parameters(v.corners_px, board, views.size, v.point_ids)
                           for v in used])
        model = joint.models[index]
        solved.append(CalibratedCamera(
            index, views, model, _camera_info(model, views.frame_id, stereo, index), mine,
            {f: i for i in mine for f in rig.frames_of[i]},
            coverage(params, [v.corners_px for v in used], views.size), orders[index],
            truth[index] if truth is not None else None))
    return RigSolution(solved, joint, rig, stereo, pairs, circles, again, offsets or [])
