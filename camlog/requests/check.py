"""``camlog check``'s request: which logs, the windows, the limit, the calibration and the
board in view."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from processors.calibration.patterns import PATTERNS

from . import fields as common
from .fields import RequestError, option
from .values import number, positive

__all__ = ["CheckRequest"]


@dataclass(frozen=True, kw_only=True)
class CheckRequest:
    """Is every log still calibrated? Drift of stereo pairs and board cameras, window by
    window."""

    epilog: ClassVar[str] = (
        "Stereo pairs are checked by the right camera's rotation relative to the left that "
        "explains the vertical error of natural features matched across the rectified "
        "pair; cameras that see a board (--size, --square) by its reprojection error. A "
        "pair is flagged from the window where its rotation, from there on, passes 5 "
        "sigmas of the log's own noise and the calibration's uncertainty; a board's window "
        "when its error passes their median by as much (--threshold replaces the limit). "
        "Writes OUTDIR/check.csv, OUTDIR/report.md, one PNG per log and OUTDIR/check.rrd; "
        "prints one line per log: clean, drifted from when and by how much, or not judged "
        "and why. Exit status: 0 every log clean, 3 a log drifted, 4 none drifted but one "
        "could not be judged (too few windows, nothing checkable), 1 an error, 2 a usage "
        "error.")

    logs: tuple[str, ...] = option((), metavar="LOG", nargs="+", batch=False,
                                   help="logs to check (paths or URIs)")
    output: Path = option(Path("check"), "-o", "--output", type=Path, metavar="OUTDIR",
                          batch=False, help="report folder (default ./check)")
    window: float = option(2.0, "--window", type=number(above=0.0, high=3600.0),
                           metavar="SEC", help="window length in seconds (default 2)")
    rate: float = option(5.0, "--rate", type=number(above=0.0, high=1000.0), metavar="HZ",
                         help="frames (stereo pairs) looked at per second of log (default 5)")
    threshold: float | None = option(
        None, "--threshold", type=positive, metavar="X",
        help="flag windows above X (px: vertical error, reprojection error) instead of the "
             "measured limit")
    calibration: Path | None = option(
        None, "--calibration", type=Path, metavar="DIR|YAML",
        help="check this calibration instead of the log's camera_info: a calibrate output "
             "folder (left.yaml + right.yaml, or ost.yaml) or a YAML file")
    camera: tuple[str, ...] = option((), "--camera", action="append", metavar="NS",
                                     help="check only this camera (namespace or image "
                                          "topic); repeatable")
    size: str | None = option(None, "-s", "--size", metavar="COLSxROWS",
                              help="a board in view: its size in inner corners, e.g. 7x6")
    square: float | None = option(None, "-q", "--square", type=positive, metavar="M",
                                  help="a board in view: its square side in metres")
    pattern: str = option("chessboard", "-p", "--pattern", choices=PATTERNS,
                          help="the board's kind (default chessboard)")
    progress: bool | None = common.progress()

    def __post_init__(self) -> None:
        if (self.size is None) != (self.square is None):
            raise RequestError(CheckRequest, "a board needs both {size} and {square}")
