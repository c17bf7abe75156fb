"""The plain OpenCV calibration of each corpus dataset: what a user would write by hand.

Chessboard: ``findChessboardCorners`` + ``cornerSubPix``; ChArUco: ``CharucoDetector``;
circles: ``findCirclesGrid`` (clustering when the plain search fails). Then
``calibrateCamera`` (k1, k2, p1, p2; ``CALIB_RATIONAL_MODEL`` for rational_polynomial) or
``fisheye.calibrate``, and for a pair ``stereoCalibrate`` with the intrinsics fixed.

    python -m benchmarks.corpus.reference [--cache DIR] [--only NAME…]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from .manifest import Board, CorpusError, Dataset, default_cache, load_manifest

SUBPIX = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
Points = NDArray[np.float32]


def _fisheye_flag(name: str) -> int:
    """OpenCV 4's ``cv2.fisheye.CALIB_*`` flags are ``cv2.CALIB_*`` in OpenCV 5."""
    return int(getattr(cv2.fisheye, name, None) or getattr(cv2, name))


@dataclass(frozen=True)
class CameraResult:
    """One camera's OpenCV calibration: views used, RMS (px) and the pinhole terms."""

    views: int
    rms_px: float
    fx: float
    fy: float
    cx: float
    cy: float


@dataclass(frozen=True)
class ReferenceResult:
    """A dataset's OpenCV calibration (``cameras`` = [mono] or [left, right])."""

    cameras: list[CameraResult]
    stereo_rms_px: float | None = None
    baseline_m: float | None = None


def board_points(board: Board) -> Points:
    """(N, 3) float32 board points in metres, in OpenCV's detection order."""
    cols, rows = board.cols_rows
    grid = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2).astype(np.float32)
    if board.pattern == "acircles":
        grid[:, 0] = 2 * grid[:, 0] + grid[:, 1] % 2
    points = np.zeros((cols * rows, 3), np.float32)
    points[:, :2] = grid * board.square_m
    return points


def detect(gray: NDArray[np.uint8], board: Board) -> tuple[Points, Points] | None:
    """(object points (N, 3), image points (N, 1, 2)) of one image, or None."""
    size = board.cols_rows
    if board.pattern == "chessboard":
        flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
        found, corners = cv2.findChessboardCorners(gray, size, flags=flags)
        if not found:
            return None
        corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), SUBPIX)
        return board_points(board), corners.astype(np.float32)
    if board.pattern in {"circles", "acircles"}:
        grid = (cv2.CALIB_CB_SYMMETRIC_GRID if board.pattern == "circles"
                else cv2.CALIB_CB_ASYMMETRIC_GRID)
        for flags in (grid, grid | cv2.CALIB_CB_CLUSTERING):
            found, centres = cv2.findCirclesGrid(gray, size, flags=flags)
            if found:
                return board_points(board), centres.astype(np.float32)
        return None
    return _detect_charuco(gray, board)


def _detect_charuco(gray: NDArray[np.uint8], board: Board) -> tuple[Points, Points] | None:
    if board.marker_m is None or board.dictionary is None:
        raise CorpusError(f"charuco board {board.size} needs marker_m and dictionary")
    cols, rows = board.cols_rows  # squares
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, board.dictionary))
    charuco = cv2.aruco.CharucoBoard((cols, rows), board.square_m, board.marker_m, dictionary)
    charuco.setLegacyPattern(board.legacy_pattern)
    corners, ids, _markers, _marker_ids = cv2.aruco.CharucoDetector(charuco).detectBoard(gray)
    if ids is None or len(ids) < 6:
        return None
    objects = np.asarray(charuco.getChessboardCorners(), np.float32)[ids.ravel()]
    return objects, corners.astype(np.float32)


def _gray(path: Path) -> NDArray[np.uint8]:
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise CorpusError(f"{path}: not an image OpenCV reads")
    return np.asarray(image, np.uint8)


def _calibrate(objects: list[Points], images: list[Points], size: tuple[int, int],
               model: str) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    if model == "equidistant":
        flags = (_fisheye_flag("CALIB_RECOMPUTE_EXTRINSIC") | _fisheye_flag("CALIB_FIX_SKEW")
                 | _fisheye_flag("CALIB_USE_INTRINSIC_GUESS"))
        focal_px = max(size) / np.pi  # an equidistant lens seeing 180 degrees across
        k0 = np.array([[focal_px, 0, (size[0] - 1) / 2], [0, focal_px, (size[1] - 1) / 2],
                       [0, 0, 1]])
        rms, k, d, *_ = cv2.fisheye.calibrate(
            [o.reshape(1, -1, 3).astype(np.float64) for o in objects],
            [i.reshape(1, -1, 2).astype(np.float64) for i in images], size, k0, np.zeros(4),
            flags=flags, criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-9))
    else:
        flags = cv2.CALIB_RATIONAL_MODEL if model == "rational_polynomial" else cv2.CALIB_FIX_K3
        rms, k, d, *_ = cv2.calibrateCamera(objects, images, size, None, None, flags=flags)
    return float(rms), np.asarray(k), np.asarray(d)


def _result(views: int, rms: float, k: NDArray[np.float64]) -> CameraResult:
    return CameraResult(views, rms, float(k[0, 0]), float(k[1, 1]), float(k[0, 2]),
                        float(k[1, 2]))


def reference_calibration(dataset: Dataset, folder: Path) -> ReferenceResult:
    """Calibrate ``folder`` (a fetched dataset) as plain OpenCV does."""
    names = sorted(Path(f).name for f in dataset.files)
    if not dataset.stereo:
        found = [(p, detect(_gray(folder / p), dataset.board)) for p in names]
        hits = [d for _p, d in found if d is not None]
        if len(hits) < 3:
            raise CorpusError(f"{dataset.name}: OpenCV found the board in {len(hits)} views")
        size = _gray(folder / names[0]).shape[::-1]
        rms, k, _d = _calibrate([o for o, _i in hits], [i for _o, i in hits], size,
                                dataset.model)
        return ReferenceResult([_result(len(hits), rms, k)])
    pairs = [(n, "right" + n[4:]) for n in names if n.startswith("left")]
    objects: list[Points] = []
    lefts: list[Points] = []
    rights: list[Points] = []
    for left, right in pairs:
        found_left = detect(_gray(folder / left), dataset.board)
        found_right = detect(_gray(folder / right), dataset.board)
        if found_left is not None and found_right is not None:
            objects.append(found_left[0])
            lefts.append(found_left[1])
            rights.append(found_right[1])
    if len(objects) < 3:
        raise CorpusError(f"{dataset.name}: OpenCV found the board in {len(objects)} pairs")
    size = _gray(folder / pairs[0][0]).shape[::-1]
    cams = [_calibrate(objects, side, size, dataset.model) for side in (lefts, rights)]
    if dataset.model == "equidistant":
        fisheye_pair = cv2.fisheye.stereoCalibrate(
            [o.reshape(1, -1, 3).astype(np.float64) for o in objects],
            [p.reshape(1, -1, 2).astype(np.float64) for p in lefts],
            [p.reshape(1, -1, 2).astype(np.float64) for p in rights],
            cams[0][1], cams[0][2], cams[1][1], cams[1][2], size,
            flags=_fisheye_flag("CALIB_FIX_INTRINSIC"))
        stereo_rms, translation = float(fisheye_pair[0]), np.asarray(fisheye_pair[6])
    else:
        pinhole_pair = cv2.stereoCalibrate(
            objects, lefts, rights, cams[0][1], cams[0][2], cams[1][1], cams[1][2], size,
            flags=cv2.CALIB_FIX_INTRINSIC)
        stereo_rms, translation = float(pinhole_pair[0]), np.asarray(pinhole_pair[6])
    return ReferenceResult([_result(len(objects), rms, k) for rms, k, _d in cams],
                           stereo_rms_px=stereo_rms,
                           baseline_m=float(np.linalg.norm(translation)))


def main() -> int:
    """Print the OpenCV reference of every fetched dataset."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", type=Path, default=default_cache())
    parser.add_argument("--only", nargs="+", metavar="NAME")
    args = parser.parse_args()
    for dataset in load_manifest():
        if args.only and dataset.name not in args.only:
            continue
        try:
            result = reference_calibration(dataset, args.cache / dataset.name)
        except (CorpusError, cv2.error) as error:
            print(f"{dataset.name}: FAILED: {str(error).strip().splitlines()[-1]}")
            continue
        cams = "; ".join(f"{c.views} views RMS {c.rms_px:.3f} px fx {c.fx:.1f} fy {c.fy:.1f} "
                         f"cx {c.cx:.1f} cy {c.cy:.1f}" for c in result.cameras)
        pair = (f"; stereo RMS {result.stereo_rms_px:.3f} px baseline "
                f"{result.baseline_m:.4f} m" if result.baseline_m is not None else "")
        print(f"{dataset.name}: {cams}{pair}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
