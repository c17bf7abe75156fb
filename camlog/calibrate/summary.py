"""The calibration summary: every figure a run produced, as a typed record.

The same record goes to ``calibration.json``, to ``/calibration/summary`` in
``calibration.mcap``, to the Markdown report and to the command's printout.
"""

from __future__ import annotations

import numpy as np

from processors.calibration.beyond import beyond_boards, reached
from processors.calibration.board import Board
from processors.calibration.joint import JointResult
from processors.calibration.model_order import OrderChoice, order_label
from processors.calibration.mono import CalibrationOptions, max_projection_difference
from processors.calibration.rig import angle_deg
from processors.calibration.rotation import rotation_vectors
from processors.calibration.uncertainty import error_against
from processors.calibration.validation import projection_difference
from processors.calibration.warp import warp_text
from replay.geometry import invert
from replay.messages import F64
from replay.records import calibration as records
from replay.records import rig as rig_records
from replay.records.scenario import Scenario

from .log_calibration import log_calibration, log_stereo_calibration
from .offsets import offset_record, true_offset_ms
from .rig_pairs import PairSolution
from .solving import CalibratedCamera, RigSolution
from .statistics import CameraStatistics
from .truth import TrueRig, true_rig

__all__ = ["build_summary"]


def _parameters(camera: CalibratedCamera, joint: JointResult
                ) -> dict[str, records.ParameterEstimate]:
    std = joint.std[camera.index]
    truth = camera.truth.parameters() if camera.truth is not None else {}
    table = {}
    for name, value in joint.parameters(camera.index).items():
        estimate = records.ParameterEstimate(float(value), float(std.get(name, 0.0)))
        if name in truth:
            estimate = records.ParameterEstimate(estimate.value, estimate.std, truth[name],
                                         float(value - truth[name]))
        table[name] = estimate
    return table


def _tangential(joint: JointResult, camera: int) -> records.TangentialSummary:
    test = joint.tangential_tests[camera]
    estimated = joint.options[camera].tangential == "estimate"
    if test is None:
        return records.TangentialSummary(estimated)
    return records.TangentialSummary(estimated, test.chi2, test.p_value, test.describe())


def _lens_order(order: OrderChoice | None) -> records.LensOrderSummary | None:
    if order is None:
        return None
    return records.LensOrderSummary(
        [order_label(c) for c in order.candidates], order.held_out_rms_px,
        order_label(order.options), order.views, order.folds, order.describe())


def _board_warp(joint: JointResult, mode: str) -> records.BoardWarpSummary | None:
    """The board's warp and, with ``auto``, its cross-validation (None: held flat, ``off``)."""
    if mode == "off":
        return None
    choice, estimate = joint.warp_choice, joint.board_warp_m
    words = [warp_text(*estimate)] if estimate is not None else []
    words.append(choice.describe() if choice is not None else "estimated (--board-warp on)")
    numbers = {} if estimate is None else {
        "warp_mm": (1000 * estimate[0]).tolist(), "warp_std_mm": (1000 * estimate[1]).tolist()}
    if choice is not None and choice.why_not is None:
        numbers |= {"held_out_rms_px": list(choice.held_out_rms_px), "gain": choice.gain,
                    "p_value": choice.p_value, "views": choice.views, "folds": choice.folds}
    return records.BoardWarpSummary(mode, estimate is not None, "; ".join(words), **numbers)


def _rejected(camera: CalibratedCamera, solved: RigSolution) -> list[records.RejectedView]:
    """Frames rejected at detection or by the speed limit (in frame order), then the views
    the solver left out (in the order of their first frames)."""
    views, joint = camera.views, solved.joint
    rejected = []
    for f in views.distinct():
        if f.detection is not None and not f.detection.accepted:
            rejected.append(records.RejectedView(f.stamp_ns, f.detection.reason))
        elif f.reason:
            rejected.append(records.RejectedView(f.stamp_ns, f.reason))
    left_out = sorted((solved.first_frame(v), joint.rejected[v]) for v in camera.view_ids
                      if v in joint.rejected)
    rejected += [records.RejectedView(views.frames[frame].stamp_ns, why)
                 for frame, why in left_out]
    return rejected


def _evidence(camera: CalibratedCamera, solved: RigSolution) -> records.EvidenceSummary:
    joint, frames_of = solved.joint, solved.rig.frames_of
    used = solved.used_views(camera)
    reasons = [joint.rejected[i] for i in camera.view_ids if i in joint.rejected]
    return records.EvidenceSummary(
        frames_used=sum(len(frames_of[v]) for v in used),
        views=len(used), held_views=sum(len(frames_of[v]) > 1 for v in used),
        outlier_views=sum("outlier" in r for r in reasons),
        blurred_views=sum("motion blur" in r for r in reasons),
        outlier_corners=sum(int((~joint.inliers[v]).sum()) for v in used),
        corner_noise_px=joint.sigma_px, frame_scatter_px=solved.rig.frame_scatter_px,
        blur=joint.blur.describe() if joint.blur is not None else None,
        measured_again=solved.measured_again[camera.index] if solved.measured_again
        else None)


def _median_worst(error_px: F64) -> tuple[float, float]:
    """Median and largest length of pixel errors ``(..., 2)``."""
    length = np.linalg.norm(error_px, axis=-1)
    return float(np.nanmedian(length)), float(np.nanmax(length))


def _uncertainty(camera: CalibratedCamera, statistics: CameraStatistics, solved: RigSolution,
                 truth: TrueRig | None) -> records.UncertaintySummary:
    index = camera.index
    u, far, validation = statistics.uncertainty, statistics.rays_uncertainty, \
        statistics.cross_validation
    true: dict[str, float] = {}
    if camera.truth is not None:
        true_model = camera.truth.model()
        aligned = projection_difference(camera.model, true_model, far.pixels)
        true["aligned_true_error_median_px"] = float(np.nanmedian(aligned))
        true["aligned_true_error_worst_px"] = float(np.nanmax(aligned))
        if truth is not None and truth.reference_from_board:
            for prefix, umap in (("", u), ("rays_", far)):
                error = error_against(
                    solved.joint.problem, index, true_model,
                    true_camera_from_reference=truth.camera_from_reference[index],
                    true_reference_from_board=truth.reference_from_board,
                    range_m=umap.range_m, pixels=umap.pixels)
                median, worst = _median_worst(error)
                true[f"{prefix}true_error_median_px"] = median
                true[f"{prefix}true_error_worst_px"] = worst
    beyond = beyond_boards(u.pixels, np.fmax(u.sigma_px, far.sigma_px),
                           reached(camera.views.size, solved.used_corners(camera)))
    left_out = statistics.left_out_px
    return records.UncertaintySummary(
        range_m=u.range_m, median_px=u.median_px, worst_px=u.worst_px,
        rays_median_px=far.median_px, rays_worst_px=far.worst_px,
        cross_validation_median_px=validation.median_px if validation is not None else None,
        cross_validation_worst_px=validation.worst_px if validation is not None else None,
        **true,
        left_out_worst_px=float(np.nanmax(left_out)) if left_out is not None else None,
        beyond_boards_px=beyond.worst_px if beyond is not None else None,
        beyond_boards_share=beyond.share if beyond is not None else None,
        beyond_boards_where=beyond.where if beyond is not None else None)


def _camera(camera: CalibratedCamera, statistics: CameraStatistics, solved: RigSolution, *,
            truth: TrueRig | None, scenario: Scenario | None, board: Board
            ) -> records.CameraSummary:
    views, joint = camera.views, solved.joint
    distinct = list(views.distinct())
    differences: dict[str, float] = {}
    if camera.truth is not None:
        seen = np.concatenate(solved.used_corners(camera))
        true_model = camera.truth.model()
        for key, within in (("", None), ("_covered", seen)):
            differences[f"max_projection_difference_vs_truth{key}_px"] = \
                max_projection_difference(camera.model, true_model, within=within)
            differences[f"max_projection_difference_vs_truth{key}_aligned_px"] = \
                max_projection_difference(camera.model, true_model, within=within,
                                          align_rotation=True)
    return records.CameraSummary(
        namespace=views.source.namespace, image_topic=views.source.image_topic,
        width=views.size[0], height=views.size[1], frames=len(views.frames),
        distinct_frames=len(distinct),
        boards_found=sum(f.detection is not None for f in distinct),
        candidate_views=len(solved.rig.candidates[camera.index]),
        selected_views=len(camera.view_of), used_views=len(solved.used_views(camera)),
        rejected=_rejected(camera, solved), rms_px=joint.rms_px,
        distortion_model=camera.model.distortion_model,
        parameters=_parameters(camera, joint),
        cross_validation_px=statistics.cross_validation_px,
        tangential=_tangential(joint, camera.index),
        coverage=records.CoverageSummary(
            {name: records.RangeProgress(lo, hi, p)
             for name, (lo, hi, p) in camera.coverage.ranges.items()},
            camera.coverage.image_cells),
        **differences,
        evidence=_evidence(camera, solved),
        uncertainty=_uncertainty(camera, statistics, solved, truth),
        lens_order=_lens_order(camera.order),
        time_offset=_time_offset(camera, solved, scenario),
        log_calibration=log_calibration(camera, solved, board),
    )


def _time_offset(camera: CalibratedCamera, solved: RigSolution, scenario: Scenario | None
                 ) -> records.TimeOffsetSummary | None:
    """A camera's time offset against camera 0, when it was measured (cameras 1..N-1)."""
    found = [o for o in solved.offsets if o.camera == camera.index]
    if not found:
        return None
    offset = found[0]
    reference = solved.cameras[0].views.source.namespace
    truth = true_offset_ms(scenario, [c.views for c in solved.cameras], camera.index)
    measured = offset.measured
    return records.TimeOffsetSummary(
        reference, offset.describe(), offset.applied,
        None if measured is None else offset_record(
            measured, reference, camera.views.source.namespace),
        truth, None if truth is None or measured is None else measured.offset_ms - truth)


def _stereo(solved: RigSolution) -> records.StereoSummary:
    assert solved.stereo is not None
    s = solved.stereo
    left, right = solved.cameras
    truth = None
    if left.truth is not None and right.truth is not None:
        right_from_left = np.linalg.inv(right.truth.world_from_camera) @ \
            left.truth.world_from_camera
        true_baseline = float(np.linalg.norm(right_from_left[:3, 3]))
        truth = records.StereoTruth(true_baseline,
                            100 * (s.baseline_m - true_baseline) / true_baseline)
    return records.StereoSummary(
        rms_px=s.rms_px, epipolar_rms_px=s.epipolar_rms_px, baseline_m=s.baseline_m,
        baseline_std_m=s.baseline_std_m, square_m=s.square_m, rotation_deg=s.rotation_deg,
        translation_m=s.right_from_left[:3, 3].tolist(), joint_views=len(s.view_epipolar_px),
        rotation_std_deg=s.rotation_std_deg,
        rejected=[records.RejectedJointView(
            left.views.frames[solved.first_frame(lv)].stamp_ns,
            right.views.frames[solved.first_frame(rv)].stamp_ns, why)
            for (lv, rv), why in s.rejected.items()],
        truth=truth, log_calibration=log_stereo_calibration(solved))


def _rig_camera(camera: CalibratedCamera, solved: RigSolution,
                reference: CalibratedCamera) -> rig_records.RigCameraSummary:
    pose = solved.joint.camera_from_reference[camera.index]
    std = np.sqrt(np.maximum(np.diag(solved.joint.rig_covariance[camera.index]), 0.0))
    truth = None
    if camera.truth is not None and reference.truth is not None:
        true_pose = invert(camera.truth.world_from_camera) @ reference.truth.world_from_camera
        truth = rig_records.RigCameraTruth(
            rotation_vectors(true_pose[None, :3, :3])[0].tolist(), true_pose[:3, 3].tolist(),
            rotation_vectors((pose[:3, :3] @ true_pose[:3, :3].T)[None])[0].tolist(),
            (pose[:3, 3] - true_pose[:3, 3]).tolist())
    return rig_records.RigCameraSummary(
        camera.views.source.namespace, camera.views.frame_id,
        rotation_vectors(pose[None, :3, :3])[0].tolist(), std[:3].tolist(),
        pose[:3, 3].tolist(), std[3:].tolist(), angle_deg(pose[:3, :3]), truth)


def _rig_pair(cameras: list[CalibratedCamera], pair: PairSolution) -> rig_records.RigPairSummary:
    first, second, s = cameras[pair.first], cameras[pair.second], pair.result
    truth = None
    if first.truth is not None and second.truth is not None:
        true_pose = invert(second.truth.world_from_camera) @ first.truth.world_from_camera
        truth = rig_records.RigPairTruth(float(np.linalg.norm(true_pose[:3, 3])),
                                         angle_deg(true_pose[:3, :3]))
    return rig_records.RigPairSummary(
        first.views.source.namespace, second.views.source.namespace, len(s.view_epipolar_px),
        s.baseline_m, s.baseline_std_m, s.rotation_deg, s.rotation_std_deg,
        s.right_from_left[:3, 3].tolist(), s.rms_px, s.epipolar_rms_px, truth)


def _rig(solved: RigSolution) -> rig_records.RigSummary:
    cameras = solved.cameras
    return rig_records.RigSummary(
        cameras[0].views.source.namespace, "camera_from_reference",
        [_rig_camera(c, solved, cameras[0]) for c in cameras],
        [_rig_pair(cameras, pair) for pair in solved.pairs])


def build_summary(solved: RigSolution, statistics: list[CameraStatistics], *,
                  board: Board, options: CalibrationOptions,
                  scenario: Scenario | None) -> records.CalibrationSummary:
    """The summary of a run from its solution and each camera's ``statistics`` (in camera
    order); ``scenario``: the simulator's record, when the log has one."""
    cameras, stereo, circles = solved.cameras, solved.stereo, solved.circles
    truth = true_rig(solved.rig, [c.views for c in cameras], [c.truth for c in cameras],
                     board=board, scenario=scenario)
    return records.CalibrationSummary(
        board=records.BoardSummary(
            board.pattern, board.cols, board.rows, board.square_m,
            circles.diameter_m if circles is not None else None,
            circles.measured if circles is not None else None),
        options=records.OptionsSummary(options.fix_principal_point, options.fix_aspect_ratio,
                               options.tangential, options.radial_count,
                               options.distortion_model, options.choose_order or None),
        cameras=[_camera(c, s, solved, truth=truth, scenario=scenario, board=board)
                 for c, s in zip(cameras, statistics, strict=True)],
        ground_truth=scenario is not None,
        stereo=_stereo(solved) if stereo is not None else None,
        rig=_rig(solved) if stereo is None and len(cameras) > 1 else None,
        board_warp=_board_warp(solved.joint, options.board_warp),
    )
