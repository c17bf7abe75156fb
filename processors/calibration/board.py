"""Calibration targets: a chessboard counted by its inner corners, as camera_calibration does."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from replay.messages import F64

from ..errors import ProcessorError

PATTERNS = ("chessboard",)


@dataclass(frozen=True)
class Board:
    """``cols`` x ``rows`` inner corners, ``square_m`` apart.

    Corners are ordered row by row (x fastest) as OpenCV reports them; the board frame has its
    origin at the first corner, x along a row, y along a column, z into the board.
    """

    cols: int
    rows: int
    square_m: float
    pattern: str = "chessboard"

    @property
    def corner_count(self) -> int:
        """Number of inner corners."""
        return self.cols * self.rows

    @property
    def pattern_size(self) -> tuple[int, int]:
        """OpenCV ``patternSize`` (corners per row, corners per column)."""
        return (self.cols, self.rows)

    def points_in_board(self) -> F64:
        """Corner positions ``(cols * rows, 3)`` in metres, z = 0."""
        xs, ys = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        grid = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
        return np.asarray(grid * self.square_m, dtype=np.float64)

    def grid(self) -> np.ndarray:
        """Integer grid coordinates ``(cols * rows, 2)`` as (col, row)."""
        xs, ys = np.meshgrid(np.arange(self.cols), np.arange(self.rows))
        return np.column_stack([xs.ravel(), ys.ravel()])

    def describe(self) -> str:
        """The board in words, e.g. ``7x6 inner corners, 0.01 m squares``."""
        return f"{self.cols}x{self.rows} inner corners, {self.square_m:g} m squares"


def parse_size(text: str) -> tuple[int, int]:
    """``"7x6"`` -> (7, 6); inner corners per row x per column."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not match:
        raise ProcessorError(f"board size must look like 7x6 (inner corners), got {text!r}")
    cols, rows = int(match[1]), int(match[2])
    if cols < 2 or rows < 2:
        raise ProcessorError(f"a board needs at least 2x2 inner corners, got {text!r}")
    return cols, rows


def make_board(size: str, square_m: float, pattern: str = "chessboard") -> Board:
    """A board from ``COLSxROWS`` inner corners, the square side in metres and the pattern."""
    if pattern not in PATTERNS:
        raise ProcessorError(f"unsupported pattern {pattern!r} (supported: {', '.join(PATTERNS)})")
    if not square_m > 0:
        raise ProcessorError(f"--square must be > 0 metres, got {square_m}")
    cols, rows = parse_size(size)
    return Board(cols, rows, square_m, pattern)
