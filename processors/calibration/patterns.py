"""The calibration target patterns, the default ArUco dictionary and the board warp's modes,
without loading numpy or OpenCV (for ``camlog calibrate``'s argument parser)."""

from __future__ import annotations

__all__ = ["DEFAULT_DICTIONARY", "PATTERNS", "WARP_MODES"]

#: ``--pattern`` names: a chessboard, a ChArUco board, a symmetric or an asymmetric circle grid
PATTERNS = ("chessboard", "charuco", "circles", "acircles")
#: the ArUco dictionary of a ChArUco board unless one is named (ROS camera_calibration's too)
DEFAULT_DICTIONARY = "DICT_5X5_100"
#: the board's warp (:mod:`.warp`): chosen by cross-validation, always estimated, held flat
WARP_MODES = ("auto", "on", "off")
