"""The plain OpenCV stereo calibration a user would write instead of ``camlog calibrate``.

Reads ``left*`` / ``right*`` image pairs from a folder, detects the chessboard, calibrates
each camera (k1, k2, p1, p2), then the pair with the intrinsics fixed, and rectifies.

    python benchmarks/opencv_stereo.py FOLDER COLSxROWS SQUARE_M
"""

import sys
from pathlib import Path

import cv2
import numpy as np

folder, size, square_m = Path(sys.argv[1]), sys.argv[2], float(sys.argv[3])
cols, rows = (int(n) for n in size.split("x"))
board_points = np.zeros((rows * cols, 3), np.float32)
board_points[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
criteria = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 30, 0.001)
corners: dict[str, list[np.ndarray]] = {"left": [], "right": []}
image_size = (0, 0)
for left_path in sorted(folder.glob("left*")):
    pair = {"left": left_path, "right": left_path.with_name("right" + left_path.name[4:])}
    grays = {side: cv2.imread(str(path), cv2.IMREAD_GRAYSCALE) for side, path in pair.items()}
    found = {side: cv2.findChessboardCorners(gray, (cols, rows))
             for side, gray in grays.items() if gray is not None}
    if len(found) == 2 and all(ok for ok, _points in found.values()):
        for side, (_ok, points) in found.items():
            gray = grays[side]
            assert gray is not None
            corners[side].append(cv2.cornerSubPix(gray, points, (11, 11), (-1, -1), criteria))
            image_size = gray.shape[::-1]
objects = [board_points] * len(corners["left"])
flags = cv2.CALIB_FIX_K3
rms_l, k_l, d_l, *_ = cv2.calibrateCamera(objects, corners["left"], image_size, None, None,
                                          flags=flags)
rms_r, k_r, d_r, *_ = cv2.calibrateCamera(objects, corners["right"], image_size, None, None,
                                          flags=flags)
stereo = cv2.stereoCalibrate(objects, corners["left"], corners["right"], k_l, d_l, k_r, d_r,
                             image_size, flags=cv2.CALIB_FIX_INTRINSIC)
rms, rotation, translation = stereo[0], stereo[5], stereo[6]
cv2.stereoRectify(k_l, d_l, k_r, d_r, image_size, rotation, translation)
print(f"{len(objects)} pairs: RMS left {rms_l:.3f} right {rms_r:.3f} stereo {rms:.3f} px, "
      f"baseline {np.linalg.norm(translation):.4f} m")
