"""``camlog calibrate``: calibration of a mono camera, a stereo pair or a rig of cameras from a
log."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

from processors.calibration.patterns import DEFAULT_DICTIONARY, PATTERNS
from replay.format_names import CAMERA_MODELS, MODEL_ALIASES

from ..errors import UsageError
from .args import (
    add_no_progress,
    add_overwrite,
    add_recover,
    name,
    non_negative,
    output_path,
    positive,
    print_warnings,
)

if TYPE_CHECKING:
    from processors.calibration.board import Board
    from processors.calibration.options import CalibrationOptions
    from replay.records import RigSummary

#: ROS distortion_model names (and OpenCV's "fisheye" for equidistant)
MODELS = (*CAMERA_MODELS, *MODEL_ALIASES)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``calibrate`` arguments (camera_calibration's vocabulary)."""
    p.epilog = (
        "Mono: --camera NS (the namespace that owns image_raw[/compressed] and camera_info, or "
        "its image topic). Stereo: --left NS --right NS; frames pair by identical stamps, "
        "or within --approximate SEC. Writes OUTDIR/{ost.yaml | left.yaml, right.yaml}, ost.txt, "
        "calibration.mcap (the log plus detections, residuals, calibrated camera_info and "
        "rectified images), calibration.json, report.md and PNG figures. "
        "Rig: --camera NS repeated, two cameras or more (or --rig NS,NS,...): every camera, "
        "every camera's pose relative to the first and every board pose solved jointly; "
        "writes one NS.yaml per camera (slashes as underscores), rig.yaml (each camera's "
        "camera_from_reference with standard deviations), calibration.json, report.md, "
        "figures and calibration.mcap. "
        "camera_calibration's spellings are accepted too: -s/--size, -q/--square, "
        "-p/--pattern, -c/--camera_name, -k/--k-coefficients, --fix-principal-point, "
        "--fix-aspect-ratio, --zero-tangent-dist, --max-chessboard-speed."
    )
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("-s", "--size", required=True, metavar="COLSxROWS",
                   help="board size in inner corners, e.g. 7x6")
    p.add_argument("-q", "--square", required=True, type=positive, metavar="M",
                   help="square side in metres, e.g. 0.01")
    p.add_argument("-p", "--pattern", default="chessboard", choices=PATTERNS,
                   help="calibration target (default chessboard)")
    p.add_argument("--camera", type=name, action="append", metavar="NS",
                   help="camera namespace, e.g. /simple_camera, or its image topic, e.g. "
                        "/simple_camera/image_raw (default: the log's only camera); repeated, "
                        "the cameras of a rig, calibrated jointly")
    p.add_argument("--rig", type=_namespaces, metavar="NS,NS,...",
                   help="the cameras of a rig, comma-separated (the same as --camera "
                        "repeated)")
    p.add_argument("--left", type=name, metavar="NS",
                   help="stereo left camera namespace (or its image topic)")
    p.add_argument("--right", type=name, metavar="NS",
                   help="stereo right camera namespace (or its image topic)")
    p.add_argument("--approximate", type=non_negative, metavar="SEC",
                   help="pair stereo frames whose stamps differ by at most SEC")
    p.add_argument("-o", "--output", type=output_path, metavar="OUTDIR",
                   help="output folder (default: LOG_calibration next to the log)")
    p.add_argument("--fix-principal-point", action="store_true",
                   help="hold the principal point at the image centre")
    p.add_argument("--fix-aspect-ratio", action="store_true", help="force fx = fy")
    tangential = p.add_mutually_exclusive_group()
    tangential.add_argument("--zero-tangent-dist", action="store_true",
                            help="hold tangential distortion p1 = p2 = 0")
    tangential.add_argument("--tangent-dist", action="store_true",
                            help="always estimate tangential distortion p1, p2 "
                                 "(camera_calibration's default; by default they are estimated "
                                 "only when the views show them, by a likelihood-ratio test)")
    p.add_argument("--model", choices=MODELS, metavar="MODEL",
                   help="lens model: plumb_bob (default), rational_polynomial or equidistant "
                        "(OpenCV's fisheye; 'fisheye' is accepted for it)")
    p.add_argument("--marker", type=float, metavar="M",
                   help="--pattern charuco: marker side in metres (--size counts squares)")
    p.add_argument("--diameter", type=positive, metavar="METRES",
                   help="--pattern circles/acircles: circle diameter in metres (default: "
                        "measured from the images)")
    p.add_argument("--dictionary", metavar="NAME",
                   help=f"--pattern charuco: OpenCV ArUco dictionary (default "
                        f"{DEFAULT_DICTIONARY})")
    p.add_argument("-k", "--k-coefficients", type=int, metavar="N",
                   help="radial coefficients to estimate (default: 2 plumb_bob, 6 "
                        "rational_polynomial, 4 equidistant); without --model, > 3 selects "
                        "rational_polynomial as camera_calibration does")
    p.add_argument("-c", "--camera-name", "--camera_name", dest="camera_name",
                   help="camera_name written in the YAML files")
    p.add_argument("--max-chessboard-speed", type=positive, metavar="PX",
                   help="reject views whose board moves more than PX pixels per frame")
    p.add_argument("--check", action="store_true",
                   help="measure --calibration files on LOG instead of calibrating")
    p.add_argument("--calibration", type=Path, action="append", metavar="YAML",
                   help="with --check: calibration file (twice for stereo: left, right)")
    add_overwrite(p)
    add_recover(p)
    p.add_argument("--no-report", action="store_true",
                   help="write only the calibration files and calibration.json: no "
                        "calibration.mcap, figures or report.md (for scripts)")
    add_no_progress(p)


def _namespaces(text: str) -> list[str]:
    """argparse type: comma-separated camera namespaces (or image topics), two or more."""
    spaces = [name(part.strip()) for part in text.split(",")]
    if len(spaces) < 2:
        raise argparse.ArgumentTypeError("a rig has two cameras or more: NS,NS,...")
    return spaces


def cameras_from(args: argparse.Namespace) -> list[str]:
    """The camera namespaces to calibrate, from the options or the log's only camera."""
    from camlog.processing.cameras import cameras_in
    from replay.formats import open_reader

    named = [*(args.camera or []), *(args.rig or [])]
    if args.left or args.right:
        if not (args.left and args.right):
            raise UsageError("stereo needs both --left and --right")
        if named:
            raise UsageError("give either --camera/--rig or --left/--right")
        return [args.left, args.right]
    if named:
        return named
    with open_reader(args.log, recover=args.recover) as reader:
        cameras = cameras_in(reader)
    # a camera's raw images first: processed images (masks, edges) are cameras of their own
    raw = {namespace for namespace, topic in cameras if "/image_raw" in topic}
    spaces = sorted(raw or {namespace for namespace, _topic in cameras})
    if len(spaces) != 1:
        raise UsageError(f"name the camera with --camera (or --left/--right); camera "
                         f"namespaces in {args.log}: {', '.join(spaces) or 'none'}")
    return spaces


def is_rig(args: argparse.Namespace) -> bool:
    """Whether the arguments name a rig: --rig, or --camera more than once."""
    return bool(args.rig) or len(args.camera or []) > 1


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


def _truth_error(camera: Any) -> str:
    u = camera.uncertainty
    if u.rays_true_error_worst_px is None:
        return ""
    return (f"; vs truth: rays median {u.rays_true_error_median_px:.3f} px, worst "
            f"{u.rays_true_error_worst_px:.3f} px")


def board_and_options(args: argparse.Namespace) -> tuple[Board, CalibrationOptions]:
    """The target and the solver options the ``calibrate`` arguments ask for."""
    from processors.calibration.board import make_board
    from processors.calibration.options import CalibrationOptions, tangential_mode

    board = make_board(args.size, args.square, args.pattern, marker_m=args.marker,
                       dictionary=args.dictionary)
    if args.diameter is not None:
        if not board.circle_grid:
            raise UsageError("--diameter belongs to circle grids (--pattern circles or "
                             "acircles)")
        if args.diameter >= board.nearest_m:
            raise UsageError(f"circles {args.diameter:g} m across would overlap at a spacing "
                             f"of {board.square_m:g} m (at most {board.nearest_m:.4g} m)")
    options = CalibrationOptions(
        fix_principal_point=args.fix_principal_point, fix_aspect_ratio=args.fix_aspect_ratio,
        tangential=tangential_mode(args.zero_tangent_dist, args.tangent_dist),
        k_coefficients=args.k_coefficients, model=args.model)
    return board, options


def run(args: argparse.Namespace) -> int:
    """Calibrate (or ``--check``) and print the key figures."""
    board, options = board_and_options(args)
    cameras = cameras_from(args)
    progress = False if args.no_progress else None
    if args.check:
        from ..calibrate.check import check_log

        if not args.calibration:
            raise UsageError("--check needs --calibration FILE (twice for stereo)")
        if is_rig(args):
            raise UsageError("--check measures one camera or a stereo pair (--left/--right), "
                             "not a rig")
        result = check_log(args.log, board=board, cameras=cameras,
                           calibrations=args.calibration, approximate_s=args.approximate,
                           diameter_m=args.diameter, progress=progress, recover=args.recover)
        print("\n".join(result.lines()))
        return 0
    from ..calibrate.flow import calibrate_log

    output = args.output or args.log.with_name(f"{args.log.stem}_calibration")
    run_ = calibrate_log(
        args.log, board=board, cameras=cameras, output_dir=output, options=options,
        approximate_s=args.approximate, camera_name=args.camera_name,
        max_speed_px=args.max_chessboard_speed, diameter_m=args.diameter,
        overwrite=args.overwrite, progress=progress, recover=args.recover,
        report=not args.no_report, rig=is_rig(args))
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
        if camera.tangential.summary is not None:
            print(f"  {camera.tangential.summary}")
        if camera.uncertainty is not None:
            u = camera.uncertainty
            print(f"  projection uncertainty at {u.range_m:.3f} m: median {u.median_px:.3f} px, "
                  f"worst {u.worst_px:.3f} px; rays {u.rays_median_px:.3f} / "
                  f"{u.rays_worst_px:.3f} px (1 sigma){_truth_error(camera)}")
        if camera.max_projection_difference_vs_truth_px is not None:
            print(f"  vs simulator truth: max projection difference "
                  f"{camera.max_projection_difference_vs_truth_covered_aligned_px:.3f} px "
                  "where corners were seen, "
                  f"{camera.max_projection_difference_vs_truth_aligned_px:.3f} px over the "
                  "whole image (camera frames aligned by a rotation)")
    if run_.summary.rig is not None:
        print("\n".join(rig_lines(run_.summary.rig)))
    if run_.summary.stereo is not None:
        s = run_.summary.stereo
        print(f"stereo: baseline {s.baseline_m:.5f} m, epipolar RMS "
              f"{s.epipolar_rms_px:.4f} px, square {s.square_m:.5f} m")
    print(f"wrote {run_.output_dir}/ ({', '.join(f.name for f in run_.files)}) "
          f"in {run_.wall_s:.1f} s")
    return 0
