"""``camlog calibrate``'s request: the board, the cameras, the lens model, check mode (ROS
camera_calibration's spellings accepted as aliases)."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from processors.calibration.patterns import DEFAULT_DICTIONARY, PATTERNS, WARP_MODES
from replay.lens_models import LENS_MODEL_NAMES

from . import fields as common
from .fields import RequestError, option, required
from .values import name, namespaces, non_negative, positive

if TYPE_CHECKING:
    from processors.calibration.board import Board
    from processors.calibration.options import CalibrationOptions

__all__ = ["CalibrateRequest"]

#: ``-k``'s word for a radial order chosen by cross-validation
AUTO_ORDER = "auto"


def radial_count(text: str) -> int | str:
    """A type: a number of radial coefficients (its range checked with the lens model), or
    ``auto``."""
    if text.strip().lower() == AUTO_ORDER:
        return AUTO_ORDER
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected an integer or '{AUTO_ORDER}', got {text!r}") from None


@dataclass(frozen=True, kw_only=True)
class CalibrateRequest:
    """Calibrate a mono camera, a stereo pair or a rig from a log (or ``check`` calibration
    files on it)."""

    epilog: ClassVar[str] = (
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

    log: Path = common.input_log()
    size: str = required("-s", "--size", metavar="COLSxROWS",
                         help="board size in inner corners, e.g. 7x6")
    square: float = required("-q", "--square", type=positive, metavar="M",
                             help="square side in metres, e.g. 0.01")
    pattern: str = option("chessboard", "-p", "--pattern", choices=PATTERNS,
                          help="calibration target (default chessboard)")
    camera: tuple[str, ...] = option(
        (), "--camera", type=name, action="append", metavar="NS",
        help="camera namespace, e.g. /simple_camera, or its image topic, e.g. "
             "/simple_camera/image_raw (default: the log's only camera); repeated, the cameras "
             "of a rig, calibrated jointly")
    rig: tuple[str, ...] = option(
        (), "--rig", type=namespaces, metavar="NS,NS,...",
        help="the cameras of a rig, comma-separated (the same as --camera repeated)")
    left: str | None = option(None, "--left", type=name, metavar="NS",
                              help="stereo left camera namespace (or its image topic)")
    right: str | None = option(None, "--right", type=name, metavar="NS",
                               help="stereo right camera namespace (or its image topic)")
    approximate: float | None = option(
        None, "--approximate", type=non_negative, metavar="SEC",
        help="pair stereo frames whose stamps differ by at most SEC")
    output: Path | None = common.output(
        "output folder (default: LOG_calibration next to the log)", metavar="OUTDIR",
        default=None)
    fix_principal_point: bool = option(False, "--fix-principal-point", action="store_true",
                                       help="hold the principal point at the image centre")
    fix_aspect_ratio: bool = option(False, "--fix-aspect-ratio", action="store_true",
                                    help="force fx = fy")
    zero_tangent_dist: bool = option(False, "--zero-tangent-dist", action="store_true",
                                     exclusive="tangential",
                                     help="hold tangential distortion p1 = p2 = 0")
    tangent_dist: bool = option(
        False, "--tangent-dist", action="store_true", exclusive="tangential",
        help="always estimate tangential distortion p1, p2 (camera_calibration's default; by "
             "default they are estimated only when the views show them, by a likelihood-ratio "
             "test)")
    model: str | None = option(
        None, "--model", choices=LENS_MODEL_NAMES, metavar="MODEL",
        help="lens model: plumb_bob (default), rational_polynomial or equidistant (OpenCV's "
             "fisheye; 'fisheye' is accepted for it)")
    marker: float | None = option(None, "--marker", type=float, metavar="M",
                                  help="--pattern charuco: marker side in metres (--size "
                                       "counts squares)")
    diameter: float | None = option(
        None, "--diameter", type=positive, metavar="METRES",
        help="--pattern circles/acircles: circle diameter in metres (default: measured from "
             "the images)")
    dictionary: str | None = option(
        None, "--dictionary", metavar="NAME",
        help=f"--pattern charuco: OpenCV ArUco dictionary (default {DEFAULT_DICTIONARY})")
    legacy_pattern: bool = option(
        False, "--legacy-pattern", action="store_true",
        help="--pattern charuco: the markers laid out as OpenCV before 4.6 did (it differs "
             "from today's layout when the board has an even number of rows of squares)")
    k_coefficients: int | str | None = option(
        None, "-k", "--k-coefficients", type=radial_count, metavar="N|auto",
        help="radial coefficients to estimate (default without --model: chosen per camera "
             "by cross-validation over the views among plumb_bob's k1 k2, k1 k2 k3 and "
             "rational_polynomial's k1..k6; with --model: 2 plumb_bob, 6 "
             "rational_polynomial, 4 equidistant); without --model, > 3 selects "
             "rational_polynomial as camera_calibration does; 'auto' chooses with --model "
             "plumb_bob too (k1 k2 or k1 k2 k3)")
    board_warp: str = option(
        "auto", "--board-warp", choices=WARP_MODES,
        help="the board's bow out of its plane (two parameters, a parabola along its x and "
             "along its y, as mrcal's calobject_warp): 'auto' (default) estimates it when "
             "cross-validation over the views shows it, 'on' always, 'off' holds the board "
             "flat")
    camera_name: str | None = option(None, "-c", "--camera-name", "--camera_name",
                                     help="camera_name written in the YAML files")
    max_chessboard_speed: float | None = option(
        None, "--max-chessboard-speed", type=positive, metavar="PX",
        help="reject views whose board moves more than PX pixels per frame")
    check: bool = option(False, "--check", action="store_true",
                         help="measure --calibration files on LOG instead of calibrating")
    calibration: tuple[Path, ...] = option(
        (), "--calibration", type=Path, action="append", metavar="YAML",
        help="with --check: calibration file (twice for stereo: left, right)")
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    report: bool = option(True, "--no-report", action="store_const", const=False,
                          help="write only the calibration files and calibration.json: no "
                               "calibration.mcap, figures or report.md (for scripts)")
    progress: bool | None = common.progress()

    def __post_init__(self) -> None:
        named = bool(self.camera or self.rig)
        if self.left or self.right:
            if not (self.left and self.right):
                raise RequestError(CalibrateRequest, "stereo needs both {left} and {right}")
            if named:
                raise RequestError(CalibrateRequest,
                                   "give either {camera}/{rig} or {left}/{right}")
        if self.check:
            if not self.calibration:
                raise RequestError(CalibrateRequest,
                                   "{check} needs {calibration} FILE (twice for stereo)")
            if self.is_rig:
                raise RequestError(CalibrateRequest, "{check} measures one camera or a stereo "
                                                     "pair ({left}/{right}), not a rig")

    @property
    def is_rig(self) -> bool:
        """Whether the request names a rig: ``rig``, or ``camera`` more than once."""
        return bool(self.rig) or len(self.camera) > 1

    @property
    def named_cameras(self) -> list[str]:
        """The cameras the request names (empty: the log's only camera)."""
        if self.left and self.right:
            return [self.left, self.right]
        return [*self.camera, *self.rig]

    @property
    def output_dir(self) -> Path:
        """Where the outputs go: ``output``, or LOG_calibration next to the log."""
        return self.output or self.log.with_name(f"{self.log.stem}_calibration")

    def board(self) -> Board:
        """The calibration target (a circle grid's ``diameter`` checked against it)."""
        from processors.calibration.board import make_board

        board = make_board(self.size, self.square, self.pattern, marker_m=self.marker,
                           dictionary=self.dictionary, legacy_pattern=self.legacy_pattern)
        if self.diameter is not None:
            if not board.circle_grid:
                raise RequestError(CalibrateRequest, "{diameter} belongs to circle grids "
                                                     "({pattern} circles or acircles)")
            if self.diameter >= board.nearest_m:
                raise RequestError(
                    CalibrateRequest,
                    f"circles {self.diameter:g} m across would overlap at a spacing of "
                    f"{board.square_m:g} m (at most {board.nearest_m:.4g} m)")
        return board

    def options(self) -> CalibrationOptions:
        """The solver's options: lens model and what is held fixed; the radial order is
        chosen by cross-validation (``choose_order``) unless ``-k N`` or ``--model`` is
        given, or with ``-k auto``."""
        from processors.calibration.options import CalibrationOptions, tangential_mode

        auto = self.k_coefficients == AUTO_ORDER or (self.k_coefficients is None
                                                    and self.model is None)
        return CalibrationOptions(
            fix_principal_point=self.fix_principal_point,
            fix_aspect_ratio=self.fix_aspect_ratio,
            tangential=tangential_mode(self.zero_tangent_dist, self.tangent_dist),
            k_coefficients=None if auto or self.k_coefficients is None
            else int(self.k_coefficients),
            model=self.model, choose_order=auto, board_warp=self.board_warp)
