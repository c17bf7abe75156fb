"""Calibration targets: chessboard, ChArUco and (asymmetric) circle grids.

``--size`` counts what ROS camera_calibration counts: a chessboard's inner corners, a
ChArUco board's squares (its inner corners are one fewer each way) and a circle grid's
circles. ``--square`` is the square side, or the circle spacing of a grid. A ChArUco board
printed by OpenCV before 4.6 with an even number of rows of squares has its markers in other
squares than today's layout (``legacy_pattern``, OpenCV's ``setLegacyPattern``). Points are
numbered row by row (x fastest) as OpenCV reports them; the board frame has its origin at the
first point, x along a row, y along a column, z into the board. An asymmetric circle grid
shifts every other row by half a step: point (c, r) sits at ((2c + r mod 2) s, r s), as in
OpenCV's and ROS's calibration.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from replay.messages import F64

if TYPE_CHECKING:
    import cv2

from ..errors import ProcessorError
from .patterns import DEFAULT_DICTIONARY, PATTERNS


@dataclass(frozen=True)
class Board:
    """``cols`` x ``rows`` points (chessboard and ChArUco: inner corners; circle grids:
    circles), ``square_m`` apart; ChArUco boards also have ``marker_m`` markers from
    ``dictionary``, laid out as OpenCV before 4.6 did with ``legacy_pattern``."""

    cols: int
    rows: int
    square_m: float
    pattern: str = "chessboard"
    marker_m: float = 0.0
    dictionary: str = DEFAULT_DICTIONARY
    legacy_pattern: bool = False

    @property
    def corner_count(self) -> int:
        """Number of points (inner corners or circles)."""
        return self.cols * self.rows

    @property
    def pattern_size(self) -> tuple[int, int]:
        """OpenCV ``patternSize`` (points per row, points per column)."""
        return (self.cols, self.rows)

    @property
    def partial_views(self) -> bool:
        """Whether a view may show only some of the points (ChArUco: each corner is
        identified by its markers)."""
        return self.pattern == "charuco"

    @property
    def circle_grid(self) -> bool:
        """Whether the points are the centres of circles (symmetric or asymmetric grid)."""
        return self.pattern in ("circles", "acircles")

    @property
    def nearest_m(self) -> float:
        """The smallest distance between two points (m); a circle grid's circles are
        narrower."""
        return self.square_m * (math.sqrt(2.0) if self.pattern == "acircles" else 1.0)

    @property
    def symmetric(self) -> bool:
        """Whether a half turn maps the board onto itself, so that a detector may number it
        from either end (chessboard and symmetric circle grid)."""
        return self.pattern in ("chessboard", "circles")

    def points_in_board(self) -> F64:
        """Point positions ``(cols * rows, 3)`` in metres, z = 0."""
        xs, ys = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        if self.pattern == "acircles":
            xs = 2 * xs + ys % 2
        grid = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
        return np.asarray(grid * self.square_m, dtype=np.float64)

    def grid(self) -> np.ndarray:
        """Integer grid coordinates ``(cols * rows, 2)`` as (col, row)."""
        xs, ys = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        return np.column_stack([xs.ravel(), ys.ravel()])

    def charuco(self) -> cv2.aruco.CharucoBoard:
        """The OpenCV ChArUco board (squares are one more than inner corners each way)."""
        import cv2

        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        board = cv2.aruco.CharucoBoard((self.cols + 1, self.rows + 1), self.square_m,
                                       self.marker_m, dictionary)
        board.setLegacyPattern(self.legacy_pattern)
        return board

    def describe(self) -> str:
        """The board in words, e.g. ``7x6 inner corners, 0.01 m squares``."""
        if self.pattern == "charuco":
            layout = ", legacy layout" if self.legacy_pattern else ""
            return (f"{self.cols + 1}x{self.rows + 1} squares ChArUco ({self.cols}x{self.rows} "
                    f"inner corners), {self.square_m:g} m squares, {self.marker_m:g} m "
                    f"{self.dictionary} markers{layout}")
        if self.circle_grid:
            kind = "asymmetric " if self.pattern == "acircles" else ""
            return f"{self.cols}x{self.rows} {kind}circle grid, {self.square_m:g} m spacing"
        return f"{self.cols}x{self.rows} inner corners, {self.square_m:g} m squares"


def parse_board_size(text: str) -> tuple[int, int]:
    """``"7x6"`` -> (7, 6): per row x per column."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise ProcessorError(f"board size must look like 7x6, got {text!r}")
    cols, rows = int(match[1]), int(match[2])
    if cols < 2 or rows < 2:
        raise ProcessorError(f"a board needs at least 2x2 points, got {text!r}")
    return cols, rows


def make_board(size: str, square_m: float, pattern: str = "chessboard", *,
               marker_m: float | None = None, dictionary: str | None = None,
               legacy_pattern: bool = False) -> Board:
    """The board of camera_calibration-style options (see the module docstring)."""
    if pattern not in PATTERNS:
        raise ProcessorError(f"unsupported pattern {pattern!r} (supported: {', '.join(PATTERNS)})")
    if not square_m > 0:
        raise ProcessorError(f"the square size must be > 0 metres, got {square_m}")
    cols, rows = parse_board_size(size)
    if pattern == "charuco":
        import cv2

        if cols < 3 or rows < 3:
            raise ProcessorError(f"a ChArUco board needs at least 3x3 squares, got {size!r}")
        if marker_m is None or not 0 < marker_m < square_m:
            raise ProcessorError(f"a ChArUco board needs a marker size between 0 and the square "
                                 f"({square_m:g} m), got {marker_m}")
        name = dictionary or DEFAULT_DICTIONARY
        if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
            known = sorted(n for n in dir(cv2.aruco) if n.startswith("DICT_"))
            raise ProcessorError(f"unknown ArUco dictionary {name!r} (OpenCV's: "
                                 f"{', '.join(known)})")
        board = Board(cols - 1, rows - 1, square_m, pattern, marker_m, name, legacy_pattern)
        markers = len(board.charuco().getIds())
        available = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)).bytesList.shape[0]
        if markers > available:
            raise ProcessorError(f"a {cols}x{rows} ChArUco board needs {markers} markers, "
                                 f"{name} has {available}")
        return board
    if dictionary is not None or marker_m is not None or legacy_pattern:
        raise ProcessorError("a marker size, an ArUco dictionary and the legacy layout belong "
                             "to the charuco pattern only")
    return Board(cols, rows, square_m, pattern)
