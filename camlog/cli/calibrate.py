"""``camlog calibrate``: calibration of a mono camera, a stereo pair or a rig of cameras from a
log."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any

from ..requests.arguments import request_from_args
from ..requests.calibrate import CalibrateRequest
from .args import add_request, print_warnings

if TYPE_CHECKING:
    from replay.records import LogCalibration, RigSummary


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``calibrate`` arguments (camera_calibration's vocabulary)."""
    add_request(p, CalibrateRequest)


def rig_lines(rig: RigSummary) -> list[str]:
    """A rig's poses and pairs, a line each, for the terminal."""
    lines = [f"rig (camera_from_reference, reference {rig.reference}):"]
    for camera in rig.cameras[1:]:
        lines.append(
            f"  {camera.namespace}: t [{', '.join(f'{v:.5f}' for v in camera.translation_m)}]"
            f" ± [{', '.join(f'{v:.1g}' for v in camera.translation_std_m)}] m, rotation "
            f"{camera.rotation_deg:.4f}° ± "
            f"{max(camera.rotation_std_rad) * 180 / math.pi:.2g}°")
    for pair in rig.pairs:
        lines.append(
            f"  {pair.first} → {pair.second}: baseline {pair.baseline_m:.5f} ± "
            f"{pair.baseline_std_m:.1g} m, rotation {pair.rotation_deg:.4f} ± "
            f"{pair.rotation_std_deg:.2g}°, {pair.joint_views} joint views, epipolar RMS "
            f"{pair.epipolar_rms_px:.4f} px")
    return lines


def log_calibration_line(theirs: LogCalibration) -> str:
    """The log's camera_info beside camlog's model, one line for the terminal."""
    return (f"  vs the log's {theirs.info_topic}: fx {theirs.fx:.3f} fy {theirs.fy:.3f} "
            f"cx {theirs.cx:.3f} cy {theirs.cy:.3f}, RMS on these views {theirs.rms_px:.4f} px "
            f"(camlog {theirs.camlog_rms_px:.4f}), max projection difference "
            f"{theirs.max_projection_difference_covered_px:.3f} px where corners were seen, "
            f"{theirs.max_projection_difference_px:.3f} px over the whole image (aligned)")


def _truth_error(camera: Any) -> str:
    u = camera.uncertainty
    if u.rays_true_error_worst_px is None:
        return ""
    return (f"; vs truth: rays median {u.rays_true_error_median_px:.3f} px, worst "
            f"{u.rays_true_error_worst_px:.3f} px")


def run(args: argparse.Namespace) -> int:
    """Calibrate (or ``--check``) and print the key figures."""
    request = request_from_args(CalibrateRequest, args)
    if request.check:
        from ..calibrate.check import measure_calibration

        print("\n".join(measure_calibration(request).lines()))
        return 0
    from ..calibrate.flow import calibrate_log
    from ..calibrate.markdown import time_offset_line

    run_ = calibrate_log(request)
    print_warnings(run_.warnings)
    if run_.solved.circles is not None:
        print(f"circle diameter {run_.solved.circles.describe()}")
    for camera in run_.summary.cameras:
        p = camera.parameters
        print(f"{camera.namespace}: {camera.used_views} views "
              f"({camera.boards_found} boards in {camera.distinct_frames} distinct of "
              f"{camera.frames} frames, {len(camera.rejected)} rejected), "
              f"RMS {camera.rms_px:.4f} px")
        print("  " + "  ".join(f"{name} {p[name].value:.3f} ± {p[name].std:.3f}"
                               for name in ("fx", "fy", "cx", "cy")))
        if camera.lens_order is not None:
            print(f"  {camera.lens_order.summary}")
        if camera.tangential.summary is not None:
            print(f"  {camera.tangential.summary}")
        if camera.time_offset is not None:
            line = time_offset_line(camera.time_offset)
            print(f"  {line[0].lower()}{line[1:]}")
        if camera.uncertainty is not None:
            u = camera.uncertainty
            print(f"  projection uncertainty at {u.range_m:.3f} m: median {u.median_px:.3f} px, "
                  f"worst {u.worst_px:.3f} px; rays {u.rays_median_px:.3f} / "
                  f"{u.rays_worst_px:.3f} px (1 sigma){_truth_error(camera)}")
            if u.beyond_boards_line is not None:
                print(f"  {u.beyond_boards_line}")
        if camera.max_projection_difference_vs_truth_px is not None:
            print(f"  vs simulator truth: max projection difference "
                  f"{camera.max_projection_difference_vs_truth_covered_aligned_px:.3f} px "
                  "where corners were seen, "
                  f"{camera.max_projection_difference_vs_truth_aligned_px:.3f} px over the "
                  "whole image (camera frames aligned by a rotation)")
        if camera.log_calibration is not None:
            print(log_calibration_line(camera.log_calibration))
    if run_.summary.board_warp is not None:
        print(run_.summary.board_warp.summary)
    if run_.summary.rig is not None:
        print("\n".join(rig_lines(run_.summary.rig)))
    if run_.summary.stereo is not None:
        s = run_.summary.stereo
        print(f"stereo: baseline {s.baseline_m:.5f} m, epipolar RMS "
              f"{s.epipolar_rms_px:.4f} px, square {s.square_m:.5f} m")
        if s.log_calibration is not None:
            print(f"  vs the log's camera_infos: baseline {s.log_calibration.baseline_m:.5f} m "
                  f"({s.log_calibration.baseline_difference_percent:+.2f} %), rotation "
                  f"{s.log_calibration.rotation_difference_deg:.4f}° apart")
    print(f"wrote {run_.output_dir}/ ({', '.join(f.name for f in run_.files)}) "
          f"in {run_.wall_s:.1f} s")
    return 0
