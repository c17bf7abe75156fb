"""``report.md``: the calibration summary for people."""

from __future__ import annotations

import math

from replay.records import (
    CalibrationSummary,
    CameraSummary,
    RigSummary,
    StereoSummary,
    TimeOffsetSummary,
)

__all__ = ["markdown_report"]


def _fmt(value: float) -> str:
    return f"{value:.6g}"


def _parameter_lines(camera: CameraSummary) -> list[str]:
    has_truth = camera.has_truth
    header = "| parameter | value | σ | 3σ interval |" + (" truth | error | error/σ |"
                                                         if has_truth else "")
    lines = [header, "|" + " --- |" * (header.count("|") - 1)]
    for name, p in camera.parameters.items():
        if p.std == 0:
            line = f"| {name} | {_fmt(p.value)} | fixed | |"
            if has_truth and p.truth is not None and p.error is not None:
                line += f" {_fmt(p.truth)} | {p.error:+.4g} | |"
            lines.append(line)
            continue
        lo, hi = p.value - 3 * p.std, p.value + 3 * p.std
        line = f"| {name} | {_fmt(p.value)} | {_fmt(p.std)} | [{_fmt(lo)}, {_fmt(hi)}] |"
        if has_truth and p.truth is not None and p.error is not None:
            ratio = abs(p.error) / p.std if p.std > 0 else float("inf")
            line += f" {_fmt(p.truth)} | {p.error:+.4g} | {ratio:.2f} |"
        lines.append(line)
    return lines


def time_offset_line(offset: TimeOffsetSummary) -> str:
    """A camera's time offset in words, with the simulator's truth when known."""
    truth = "" if offset.truth_ms is None else (
        f" (truth {offset.truth_ms:+.3f} ms" + ("" if offset.error_ms is None else
                                               f", error {offset.error_ms:+.3f} ms") + ")")
    return f"Time offset against {offset.reference}: {offset.summary}{truth}"


def _camera_lines(camera: CameraSummary) -> list[str]:
    lines = [
        f"## {camera.namespace}", "",
        f"{camera.frames} frames ({camera.distinct_frames} distinct), board found in "
        f"{camera.boards_found}, {camera.candidate_views} candidate views, "
        f"{camera.selected_views} selected, {camera.used_views} used. "
        f"Reprojection RMS {camera.rms_px:.4f} px.", "",
        *_parameter_lines(camera), "",
    ]
    for text in (camera.lens_order.summary if camera.lens_order is not None else None,
                 camera.tangential.summary):
        if text is not None:
            lines.append(text[0].upper() + text[1:] + ".")
    if camera.time_offset is not None:
        lines.append(time_offset_line(camera.time_offset) + ".")
    if camera.evidence is not None:
        e = camera.evidence
        held = f" ({e.held_views} of them held poses, their frames averaged)" \
            if e.held_views else ""
        lines.append(
            f"Evidence: {e.frames_used} frames in {e.views} views{held}; left out: "
            f"{e.outlier_views} views as not the board, {e.blurred_views} as too blurred, "
            f"{e.outlier_corners} single outlier corners. Corner noise {e.corner_noise_px:.3f} "
            "px per coordinate" + (f"; held frames scatter {e.frame_scatter_px:.4f} px about "
                                   "their mean" if e.frame_scatter_px is not None else "")
            + ".")
        if e.blur is not None:
            lines.append(f"Motion blur: {e.blur}.")
        if e.measured_again is not None:
            lines.append(f"Corners measured again {e.measured_again}.")
    if camera.uncertainty is not None:
        u = camera.uncertainty
        lines.append(
            f"Projection uncertainty (uncertainty.png): a point {u.range_m:.3f} m away (the "
            f"boards' median distance) projects to within {u.median_px:.3f} px (median over "
            f"the image) and {u.worst_px:.3f} px (worst, usually a corner of the image), one "
            "standard deviation in the worst direction, from the covariance of every "
            "parameter and board pose (mrcal's method); for points far away (rays) "
            f"{u.rays_median_px:.3f} px and {u.rays_worst_px:.3f} px.")
        if u.left_out_worst_px is not None:
            lines.append(
                "These figures include what the lens model leaves out: its projections differ "
                "from those of the model fitted with the terms it left out (p1 p2 the "
                "tangential test dropped, k3 beside the k1 k2 the views chose) by up to "
                f"{u.left_out_worst_px:.3f} px, added in quadrature.")
        if u.beyond_boards_line is not None:
            lines.append(u.beyond_boards_line[0].upper() + u.beyond_boards_line[1:] + ".")
        if u.cross_validation_worst_px is not None:
            lines.append(
                "Cross-validation: two halves of the evidence (every other board point of "
                "every view), calibrated separately, differ by twice the expected error of "
                "the whole; half their difference for rays, measured as the uncertainty is, is "
                f"{u.cross_validation_median_px:.3f} px (median) and "
                f"{u.cross_validation_worst_px:.3f} px (worst).")
        if u.true_error_median_px is not None and u.rays_true_error_median_px is not None:
            lines.append(
                "Against the simulator's truth, measured as the uncertainty predicts it (the "
                "point carried through the estimated board poses and back through the true "
                f"ones): {u.true_error_median_px:.3f} px (median) and "
                f"{u.true_error_worst_px:.3f} px (worst) at {u.range_m:.3f} m; for rays "
                f"{u.rays_true_error_median_px:.3f} px and {u.rays_true_error_worst_px:.3f} px.")
        if u.aligned_true_error_median_px is not None:
            lines.append(
                "Against the simulator's truth for rays after the rotation that best aligns "
                "the camera frames (as the max projection difference): "
                f"{u.aligned_true_error_median_px:.3f} px (median) and "
                f"{u.aligned_true_error_worst_px:.3f} px (worst).")
    if camera.max_projection_difference_vs_truth_px is not None:
        lines.append(
            "Against the simulator's true model, max projection difference: "
            f"{camera.max_projection_difference_vs_truth_covered_aligned_px:.3f} px "
            "where the views put corners and "
            f"{camera.max_projection_difference_vs_truth_aligned_px:.3f} px over the "
            "whole image (its corners are extrapolated), after the best rotation of the "
            "camera frame, which intrinsic calibration cannot observe; without it "
            f"{camera.max_projection_difference_vs_truth_covered_px:.3f} px and "
            f"{camera.max_projection_difference_vs_truth_px:.3f} px.")
    if camera.log_calibration is not None:
        lines += ["", *_log_calibration_lines(camera), ""]
    cov = camera.coverage
    lines.append("Coverage: " + ", ".join(
        f"{k} {100 * v.progress:.0f}%" for k, v in cov.ranges.items())
        + f", image cells {100 * cov.image_cells:.0f}%.")
    if camera.rejected:
        lines += ["", f"Rejected views ({len(camera.rejected)}):"]
        reasons: dict[str, int] = {}
        for item in camera.rejected:
            key = item.reason.split(" (")[0] if "RMS" not in item.reason else item.reason
            reasons[key] = reasons.get(key, 0) + 1
        lines += [f"- {count}× {reason}" for reason, count in reasons.items()]
    lines.append("")
    return lines


def _log_calibration_lines(camera: CameraSummary) -> list[str]:
    """The log's own calibration (camera_info) beside camlog's, on the same views."""
    theirs, p = camera.log_calibration, camera.parameters
    assert theirs is not None
    return [
        f"Beside the calibration the log carries ({theirs.info_topic}, "
        f"{theirs.distortion_model}), on the {camera.used_views} views camlog used (each "
        "view's board pose fitted to each model):", "",
        "| model | fx | fy | cx | cy | reprojection RMS (px) |",
        "| --- | --- | --- | --- | --- | --- |",
        f"| the log's camera_info | {theirs.fx:.3f} | {theirs.fy:.3f} | {theirs.cx:.3f} | "
        f"{theirs.cy:.3f} | {theirs.rms_px:.4f} |",
        f"| camlog | {p['fx'].value:.3f} | {p['fy'].value:.3f} | {p['cx'].value:.3f} | "
        f"{p['cy'].value:.3f} | {theirs.camlog_rms_px:.4f} |", "",
        "The two models image one ray up to "
        f"{theirs.max_projection_difference_covered_px:.3f} px apart where the views put "
        f"corners, {theirs.max_projection_difference_px:.3f} px over the whole image (after "
        "the rotation that best aligns the camera frames, which intrinsic calibration cannot "
        "observe).",
    ]


def _stereo_lines(s: StereoSummary) -> list[str]:
    lines = [
        "## Stereo", "",
        f"{s.joint_views} joint views. Stereo RMS {s.rms_px:.4f} px, epipolar RMS "
        f"after rectification {s.epipolar_rms_px:.4f} px.",
        f"Baseline {s.baseline_m:.6f} m (σ {s.baseline_std_m:.2g} m), rotation "
        f"{s.rotation_deg:.4f}°"
        + (f" (σ {s.rotation_std_deg:.2g}°)" if s.rotation_std_deg is not None else "")
        + f", T = [{', '.join(f'{v:.5f}' for v in s.translation_m)}] m.",
        f"Board square re-estimated by triangulation: {s.square_m:.5f} m.",
    ]
    if s.rejected:
        lines.append(f"Rejected joint views ({len(s.rejected)}):")
        lines += [f"- left {r.left_stamp_ns} ns, right {r.right_stamp_ns} ns: {r.reason}"
                  for r in s.rejected]
    if s.truth is not None:
        lines.append(f"True baseline {s.truth.baseline_m:.6f} m: error "
                     f"{s.truth.baseline_error_percent:+.3f} %.")
    if s.log_calibration is not None:
        theirs = s.log_calibration
        lines.append(f"The log's two camera_infos imply a baseline of {theirs.baseline_m:.6f} m "
                     f"(camlog's differs by {theirs.baseline_difference_percent:+.2f} %) and a "
                     f"rotation {theirs.rotation_difference_deg:.4f}° from camlog's.")
    lines.append("")
    return lines


def _rig_lines(rig: RigSummary) -> list[str]:
    lines = [
        "## Rig", "",
        f"Every camera's pose relative to {rig.reference} ({rig.convention}: X_camera = R "
        "X_reference + t), with standard deviations per axis from the joint covariance "
        "(rig.yaml holds the full poses).", "",
        "| camera | t (m) | σ t (m) | rotation (°) | σ rotation (°, per axis) |"
        + (" t error (m) | rotation error (°) |" if any(c.truth for c in rig.cameras) else ""),
        "| --- | --- | --- | --- | --- |" + (" --- | --- |" if any(c.truth for c in rig.cameras)
                                             else ""),
    ]
    for c in rig.cameras[1:]:
        line = (f"| {c.namespace} | {_vector(c.translation_m, '.5f')} | "
                f"{_vector(c.translation_std_m, '.1e')} | {c.rotation_deg:.4f} | "
                f"{_vector([math.degrees(v) for v in c.rotation_std_rad], '.1e')} |")
        if c.truth is not None:
            line += (f" {_vector(c.truth.translation_error_m, '+.1e')} | "
                     f"{_vector([math.degrees(v) for v in c.truth.rotation_error_rad], '+.1e')} |")
        lines.append(line)
    lines += ["", "Pairs that saw the board at the same instants (second_from_first; epipolar "
              "RMS of their joint views after rectifying the pair):", "",
              "| pair | joint views | baseline (m) | σ (m) | rotation (°) | σ (°) | RMS (px) | "
              "epipolar RMS (px) | true baseline (m) | true rotation (°) |",
              "|" + " --- |" * 10]
    for pair in rig.pairs:
        truth = f" {pair.truth.baseline_m:.6f} | {pair.truth.rotation_deg:.4f} |" \
            if pair.truth is not None else " | |"
        lines.append(f"| {pair.first} → {pair.second} | {pair.joint_views} | "
                     f"{pair.baseline_m:.6f} | {pair.baseline_std_m:.2g} | "
                     f"{pair.rotation_deg:.4f} | {pair.rotation_std_deg:.2g} | "
                     f"{pair.rms_px:.4f} | {pair.epipolar_rms_px:.4f} |{truth}")
    lines.append("")
    return lines


def _vector(values: list[float], spec: str) -> str:
    return "[" + ", ".join(format(v, spec) for v in values) + "]"


def markdown_report(summary: CalibrationSummary, figures: list[str]) -> str:
    """A short human summary of the calibration, with its figures."""
    board, options = summary.board, summary.options
    flags = ", ".join(name.replace("_", "-") for name, on in (
        ("fix_principal_point", options.fix_principal_point),
        ("fix_aspect_ratio", options.fix_aspect_ratio)) if on)
    circles = "" if board.diameter_m is None else (
        f"Circles {board.diameter_m:.5f} m across "
        f"({'measured from the images' if board.diameter_measured else 'given'}). ")
    lines = [
        "# Calibration report", "",
        f"Board: {board.pattern} {board.cols}x{board.rows} points, {board.square_m:g} m "
        f"spacing. {circles}"
        + ("Model: radial order chosen per camera by cross-validation over its views; "
           if options.choose_order else
           f"Model: {options.distortion_model} with {options.k_coefficients} radial "
           "coefficients; ")
        + f"options: {flags or 'none'}; tangential distortion: "
        f"{options.tangential}.", "",
    ]
    if summary.board_warp is not None:
        text = summary.board_warp.summary
        lines += [text[0].upper() + text[1:] + ".", ""]
    for camera in summary.cameras:
        lines += _camera_lines(camera)
    if summary.stereo is not None:
        lines += _stereo_lines(summary.stereo)
    if summary.rig is not None:
        lines += _rig_lines(summary.rig)
    lines += ["## Figures", ""] + [f"![{name}]({name})" for name in figures] + [""]
    return "\n".join(lines)
