"""Detection of every target kind with OpenCV's detectors: one entry point, :func:`find_board`.

Chessboards go through :func:`~.detect.find_chessboard` (with its square-by-square checks).
ChArUco boards through ``cv2.aruco.CharucoDetector``: every inner corner is identified by the
markers around it, so a board cut by the image border still gives the corners it shows —
the views near the border, where distortion is learnt. Without a camera model each corner is
placed by the homographies of its two neighbouring markers (both must be found) before its
sub-pixel refinement; given a model (a first calibration), OpenCV places every corner by the
board's pose from all the markers found and the model's projection, which is close enough on a
strongly distorted lens for a corner beside a single found marker — the corners nearest the
image border, whose second marker the border cuts. Circle grids through
``cv2.findCirclesGrid`` (symmetric or asymmetric), which needs every circle; each circle's
centre is then measured again from grey levels, with the circles' diameter (:mod:`.moments`).
"""

from __future__ import annotations

import threading

import cv2
import numpy as np

from replay.camera import CameraModel

from ..errors import ProcessorError
from .board import Board
from .detect import BORDER_PX, Detection, canonical_order, find_chessboard, track_chessboard
from .moments import disc_moments
from .opencv_lens import OPENCV_LENSES, PINHOLE

#: fewest ChArUco corners worth a view (a board pose has 6 unknowns)
MIN_CHARUCO_CORNERS = 6
#: lens models OpenCV's ChArUco detector can project through (its pinhole distortion)
GUIDING_MODELS = tuple(name for name, family in OPENCV_LENSES.items() if family is PINHOLE)
_LOCAL = threading.local()


def find_board(gray: np.ndarray, board: Board, model: CameraModel | None = None, *,
               thorough: bool = False) -> Detection | None:
    """Detect ``board`` in a ``(H, W)`` uint8 image; None when no board is found. ``model``
    (the camera's, from a first calibration) guides a ChArUco detection (see the module);
    ``thorough`` tries OpenCV's slower detectors when the fast ones find nothing (a photo,
    which no neighbouring frame can stand in for)."""
    if board.pattern == "charuco":
        return find_charuco(gray, board, model)
    if board.circle_grid:
        return find_circles(gray, board, thorough=thorough)
    return find_chessboard(gray, board, thorough=thorough)


def guides_charuco(distortion_model: str) -> bool:
    """Whether OpenCV's ChArUco detector can use a model of ``distortion_model`` (a pinhole
    lens model)."""
    return distortion_model in GUIDING_MODELS


def _charuco_detector(board: Board, model: CameraModel | None) -> cv2.aruco.CharucoDetector:
    """One detector per thread, board and guiding model (OpenCV's detectors keep state
    between calls)."""
    cache: dict[tuple[Board, bytes], cv2.aruco.CharucoDetector] = getattr(_LOCAL, "charuco", {})
    _LOCAL.charuco = cache
    key = (board, b"" if model is None else model.k.tobytes() + model.d.tobytes())
    if key not in cache:
        parameters = cv2.aruco.CharucoParameters()
        if model is not None:
            parameters.cameraMatrix = np.asarray(model.k, dtype=np.float64)
            parameters.distCoeffs = np.asarray(model.d, dtype=np.float64).reshape(1, -1)
            parameters.minMarkers = 1
        cache[key] = cv2.aruco.CharucoDetector(board.charuco(), parameters)
    return cache[key]


def find_charuco(gray: np.ndarray, board: Board, model: CameraModel | None = None
                 ) -> Detection | None:
    """The ChArUco corners seen, identified by their markers; corners within
    :data:`~.detect.BORDER_PX` of the image border are left out. A ``model`` (pinhole lens
    models only, :func:`guides_charuco`) places the corners by the board's pose."""
    if model is not None and not guides_charuco(model.distortion_model):
        raise ProcessorError(f"a {model.distortion_model} model cannot guide ChArUco detection")
    corners, ids, _markers, _marker_ids = _charuco_detector(board, model).detectBoard(gray)
    if corners is None or ids is None or len(ids) == 0:
        return None
    point_ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    corners_px = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    h, w = gray.shape
    inside = ((corners_px >= BORDER_PX) & (corners_px <= [w - 1 - BORDER_PX, h - 1 - BORDER_PX])
              ).all(axis=1)
    corners_px, point_ids = corners_px[inside], point_ids[inside]
    order = np.argsort(point_ids)
    corners_px, point_ids = corners_px[order], point_ids[order]
    if len(point_ids) < MIN_CHARUCO_CORNERS:
        return Detection(corners_px, False, f"only {len(point_ids)} ChArUco corners "
                         f"(need {MIN_CHARUCO_CORNERS})", point_ids)
    if board.charuco().checkCharucoCornersCollinear(point_ids.reshape(-1, 1).astype(np.int32)):
        return Detection(corners_px, False, "the ChArUco corners seen lie on one line",
                         point_ids)
    return Detection(corners_px, True, "", point_ids)


def find_circles(gray: np.ndarray, board: Board, *, thorough: bool = False
                 ) -> Detection | None:
    """The circles of a symmetric or asymmetric grid, all of them or none: the area centroids
    of their discs' images (grey-level moments where a circle can be measured, else the blob
    detector's), and the circles' diameter (the median over the circles). ``thorough`` tries
    ``findCirclesGrid``'s clustering search too, which finds grids seen at steep angles."""
    flags = cv2.CALIB_CB_ASYMMETRIC_GRID if board.pattern == "acircles" \
        else cv2.CALIB_CB_SYMMETRIC_GRID
    params = cv2.SimpleBlobDetector.Params()
    params.minArea = 8.0
    params.maxArea = float(gray.size) / 4.0
    params.minDistBetweenBlobs = 2.0
    detector = cv2.SimpleBlobDetector.create(params)
    found, centres = cv2.findCirclesGrid(gray, board.pattern_size, flags=flags,
                                         blobDetector=detector)
    if thorough and not found:
        found, centres = cv2.findCirclesGrid(gray, board.pattern_size,
                                             flags=flags | cv2.CALIB_CB_CLUSTERING,
                                             blobDetector=detector)
    if not found or centres is None or len(centres) != board.corner_count:
        return None
    centres_px = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    if board.symmetric:
        centres_px = canonical_order(centres_px, board)
    h, w = gray.shape
    if (centres_px < BORDER_PX).any() or (centres_px[:, 0] > w - 1 - BORDER_PX).any() \
            or (centres_px[:, 1] > h - 1 - BORDER_PX).any():
        return Detection(centres_px, False, "touches the image border")
    discs = disc_moments(gray, centres_px, board)
    measured = discs.measured
    if not measured.any():
        return Detection(centres_px, True)
    centres_px = np.where(measured[:, None], discs.centroid_px, centres_px)
    return Detection(centres_px, True, diameter_m=float(np.median(discs.diameter_m[measured])))


#: consecutive frames one detection job handles: the first is found afresh, the others
#: tracked from it when the board is a chessboard
SEGMENT_FRAMES = 8


def detect_segment(grays: list[np.ndarray], board: Board, model: CameraModel | None = None,
                   thorough: list[bool] | None = None) -> list[Detection | None]:
    """Detections of consecutive frames ``(H, W)`` uint8: the first found afresh, each next
    chessboard tracked from the previous two (their motion carried on) and found afresh
    only when tracking fails; other targets found afresh in every frame (a ChArUco board
    guided by ``model`` when given). ``thorough[i]``: frame ``i`` is a photo, searched with
    every detector when the fast ones fail (see :func:`find_board`)."""
    out: list[Detection | None] = []
    for i, gray in enumerate(grays):
        try:
            out.append(_detect_next(gray, out, board, model,
                                    thorough=thorough[i] if thorough else False))
        except cv2.error as err:  # one frame OpenCV cannot handle is that frame's reason
            message = str(err).strip().splitlines()[-1]
            out.append(Detection(np.zeros((0, 2)), False, f"OpenCV failed: {message}"))
    return out


def _detect_next(gray: np.ndarray, previous: list[Detection | None], board: Board,
                 model: CameraModel | None, *, thorough: bool) -> Detection | None:
    """The next frame's detection: tracked from the previous two when a whole chessboard
    was found in them, else found afresh."""
    last = previous[-1] if previous else None
    if board.pattern == "chessboard" and last is not None and last.accepted \
            and last.point_ids is None:
        before = previous[-2] if len(previous) > 1 else None
        velocity = last.corners_px - before.corners_px \
            if before is not None and before.accepted and before.point_ids is None \
            and np.abs(last.corners_px - before.corners_px).max() < 50 else 0.0
        found = track_chessboard(gray, last.corners_px + velocity, board)
        if found is not None:
            return found
    return find_board(gray, board, model, thorough=thorough)
