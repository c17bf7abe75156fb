"""The plain OpenCV stereo calibration a user would write for a log of two free-running cameras.

Reads both image topics of an MCAP log (``mcap_ros2``, no camlog), finds the chessboard in
every frame (``findChessboardCorners`` + ``cornerSubPix``, numbered from the board's upper end
in both cameras), pairs each left frame with the nearest right frame within ``--slop`` seconds,
and keeps a pair only when the board stood still in both cameras since their previous frame:
the cameras shoot at different instants, and a board that moved between them is at another
pose in each. Each camera is calibrated on its own still frames (k1 k2 p1 p2 k3,
``calibrateCamera``'s default flags), then the rig with ``stereoCalibrate``
(``CALIB_FIX_INTRINSIC``) on the pairs; a held pose counts once.

    python benchmarks/opencv_stereo_log.py LOG LEFT_TOPIC RIGHT_TOPIC COLSxROWS SQUARE_M
        [--slop 0.02]
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

import cv2
import numpy as np
from mcap_ros2.reader import read_ros2_messages

#: a board whose corners moved less than this (mean, px) since the previous frame stood still
STILL_PX = 0.5
#: a pair whose left corners moved less than this (mean, px) from the last pair kept is the
#: same held pose again
SAME_POSE_PX = 1.0


@dataclass(frozen=True)
class StereoResult:
    """Both cameras' ``K`` (3, 3) and ``D`` (5,), ``R`` (3, 3) and ``T`` (3,) taking left
    camera coordinates to right ones, the stereo RMS (px) and how many pairs it used."""

    k_left: np.ndarray
    d_left: np.ndarray
    k_right: np.ndarray
    d_right: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    rms_px: float
    pairs: int


def frames(path: Path, topic: str) -> list[tuple[int, np.ndarray]]:
    """Every image of ``topic`` as (stamp in ns, grey image)."""
    out = []
    for message in read_ros2_messages(str(path), topics=[topic]):
        image = message.ros_msg
        pixels = np.frombuffer(image.data, np.uint8).reshape(image.height, image.width, -1)
        code = {"rgb8": cv2.COLOR_RGB2GRAY, "bgr8": cv2.COLOR_BGR2GRAY}.get(image.encoding)
        gray = cv2.cvtColor(pixels, code) if code is not None else pixels[..., 0].copy()
        stamp = image.header.stamp
        out.append((stamp.sec * 1_000_000_000 + stamp.nanosec, gray))
    return out


def corners(images: list[tuple[int, np.ndarray]], size: tuple[int, int], *,
            window: tuple[int, int] = (11, 11)) -> list[tuple[int, np.ndarray | None]]:
    """Per frame, its stamp and the board's corners ``(N, 2)`` (None: not found), refined by
    ``cornerSubPix`` in ``window`` (half sizes, px)."""
    criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
    out: list[tuple[int, np.ndarray | None]] = []
    for stamp, gray in images:
        found, points = cv2.findChessboardCorners(gray, size)
        if found:
            points = cv2.cornerSubPix(gray, points, window, (-1, -1), criteria).reshape(-1, 2)
            if points[0, 1] > points[-1, 1]:  # OpenCV may start from either end of the board
                points = points[::-1].copy()
        out.append((stamp, points if found else None))
    return out


def still(seen: list[tuple[int, np.ndarray | None]]) -> list[bool]:
    """Per frame, whether its board stood still since the previous frame."""
    out = [False]
    for (_, before), (_, now) in pairwise(seen):
        out.append(before is not None and now is not None
                   and float(np.linalg.norm(now - before, axis=1).mean()) < STILL_PX)
    return out


def calibrate_pair(path: Path, *, left_topic: str, right_topic: str, size: tuple[int, int],
                   square_m: float, slop_s: float = 0.02) -> StereoResult:
    """The whole script on one log (see the module's docstring)."""
    left_images = frames(path, left_topic)
    shape = left_images[0][1].shape[::-1]
    left, right = corners(left_images, size), corners(frames(path, right_topic), size)
    left_still, right_still = still(left), still(right)
    board = np.zeros((size[0] * size[1], 3), np.float32)
    board[:, :2] = np.mgrid[0:size[0], 0:size[1]].T.reshape(-1, 2) * square_m
    right_ns = np.array([stamp for stamp, _ in right], dtype=np.int64)
    pairs: list[tuple[np.ndarray, np.ndarray]] = []
    for i, (stamp, left_px) in enumerate(left):
        j = int(np.argmin(np.abs(right_ns - stamp)))
        right_px = right[j][1]
        if left_px is None or right_px is None or abs(right_ns[j] - stamp) > slop_s * 1e9 \
                or not (left_still[i] and right_still[j]):
            continue
        if pairs and float(np.linalg.norm(left_px - pairs[-1][0], axis=1).mean()) \
                < SAME_POSE_PX:
            continue
        pairs.append((left_px, right_px))
    models = []
    for seen, is_still in ((left, left_still), (right, right_still)):
        views = [px for (_, px), ok in zip(seen, is_still, strict=True) if ok and px is not None]
        views = [px for k, px in enumerate(views)
                 if k == 0 or float(np.linalg.norm(px - views[k - 1], axis=1).mean())
                 >= SAME_POSE_PX]
        _rms, k, d, _r, _t = cv2.calibrateCamera([board] * len(views),
                                                 [v.astype(np.float32) for v in views],
                                                 shape, None, None)
        models.append((k, d.ravel()))
    (k_l, d_l), (k_r, d_r) = models
    rms, *_, rotation, translation, _e, _f = cv2.stereoCalibrate(
        [board] * len(pairs), [p[0].astype(np.float32) for p in pairs],
        [p[1].astype(np.float32) for p in pairs], k_l, d_l, k_r, d_r, shape,
        flags=cv2.CALIB_FIX_INTRINSIC)
    return StereoResult(k_l, d_l, k_r, d_r, rotation, np.ravel(translation), float(rms),
                        len(pairs))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    parser.add_argument("left")
    parser.add_argument("right")
    parser.add_argument("size", help="inner corners, COLSxROWS")
    parser.add_argument("square", type=float, help="square side (m)")
    parser.add_argument("--slop", type=float, default=0.02, help="pairing slop (s)")
    args = parser.parse_args()
    cols, rows = (int(n) for n in args.size.split("x"))
    result = calibrate_pair(args.log, left_topic=args.left, right_topic=args.right,
                            size=(cols, rows), square_m=args.square, slop_s=args.slop)
    angle = np.degrees(np.linalg.norm(cv2.Rodrigues(result.rotation)[0]))
    print(f"{result.pairs} pairs: stereo RMS {result.rms_px:.3f} px, baseline "
          f"{np.linalg.norm(result.translation):.4f} m, rotation {angle:.3f} deg")


if __name__ == "__main__":
    main()
