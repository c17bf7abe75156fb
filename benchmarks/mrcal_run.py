"""mrcal on camlog's detections: the request :mod:`benchmarks.mrcal_solve` reads, run under a
Python that has mrcal, and its answer as camlog camera models.

mrcal sees what a plain OpenCV script sees (:func:`~benchmarks.calibration_truth.detected`:
every distinct frame whose board passed detection, each corner at its board grid position);
for a stereo pair, the frames of each pair of views camlog made (instant by instant) share a
frame number, so mrcal sees them as one instant.
"""

from __future__ import annotations

import json
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from camlog.calibrate.flow import CalibrationRun
from processors.calibration.board import Board
from processors.calibration.robust import I64, BoardView
from replay.camera import CameraModel
from replay.messages import F64

from .calibration_truth import detected, nominal_focal_px, true_models

HELPER = Path(__file__).with_name("mrcal_solve.py")
DEFAULT_VENV = Path.home() / ".cache" / "camlog" / "mrcal-venv"
VENV_RECIPE = (f"python3.12 -m venv {DEFAULT_VENV} && {DEFAULT_VENV}/bin/pip install --no-deps "
               "'mrcal==2.5.*' numpy numpysane scipy gnuplotlib shapely packaging "
               "opencv-python-headless")
#: camlog's lens models as mrcal's (a fisheye: none, mrcal's fisheye models differ)
LENSMODELS = {"plumb_bob": "LENSMODEL_OPENCV5", "rational_polynomial": "LENSMODEL_OPENCV8"}
#: unpaired frames of the second camera are numbered from here (frame indices stay below)
UNPAIRED = 10_000_000


class MrcalError(Exception):
    """mrcal failed on one calibration (its message)."""


@dataclass(frozen=True)
class MrcalResult:
    """mrcal's models, ``right_from_left`` (4, 4) of a pair (None: mono) and its report."""

    models: list[CameraModel]
    right_from_left: F64 | None
    report: list[str]


def mrcal_available(python: Path) -> str | None:
    """None when ``python`` runs and imports mrcal, else why not (one line)."""
    if not python.exists():
        return f"no {python} (make it with: {VENV_RECIPE}; or pass --mrcal-python)"
    done = subprocess.run([str(python), "-c", "import mrcal"], capture_output=True, text=True,
                          check=False)
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1:] or ["no output"]
        return f"{python} cannot import mrcal: {last[0]}"
    return None


def _frame_numbers(run: CalibrationRun) -> list[dict[int, int]]:
    """Per camera, frame index -> mrcal frame number (shared by frames camlog paired: the
    frames of a pair's two views, instant by instant)."""
    cameras = [{f.index: f.index for f in detected(c)} for c in run.cameras]
    if len(cameras) == 2:
        rig = run.solved.rig
        partner = {rf: lf for lv, rv in rig.pairs
                   for lf, rf in zip(rig.frames_of[lv], rig.frames_of[rv], strict=True)
                   if lf in cameras[0]}
        cameras[1] = {i: partner.get(i, UNPAIRED + i) for i in cameras[1]}
    return cameras


def oriented_ids(ids: I64, corners_px: F64, view: BoardView, count: int) -> I64:
    """A frame's point ids ``(M,)`` numbered from the end of a symmetric board (of ``count``
    points) its held view numbers them from: reversed when that brings its corners
    ``(M, 2)`` nearer the view's."""
    view_px = np.full((count, 2), np.nan)
    view_px[view.point_ids] = view.corners_px
    reversed_ids = count - 1 - ids

    def gap(numbered: I64) -> float:
        return float(np.nanmean(np.linalg.norm(corners_px - view_px[numbered], axis=1)))
    return reversed_ids if gap(reversed_ids) < gap(ids) else ids


def request(run: CalibrationRun, board: Board, *, lensmodel: str,
            focal_px: float) -> dict[str, Any]:
    """The JSON request of :mod:`benchmarks.mrcal_solve` for a run's detections; on a
    symmetric board, frames in camlog's held views numbered as those views (camlog numbers
    every camera's views from the same end of the board)."""
    numbers = _frame_numbers(run)
    rig = run.solved.rig
    view_of = {(view.camera, f): view for view, frames in zip(rig.views, rig.frames_of,
                                                              strict=True) for f in frames}
    cameras = []
    for c, (camera, number_of) in enumerate(zip(run.cameras, numbers, strict=True)):
        frames: dict[str, list[list[float] | None]] = {}
        for frame in detected(camera):
            assert frame.detection is not None
            ids, corners = frame.detection.ids, frame.detection.corners_px
            if board.symmetric and (view := view_of.get((c, frame.index))) is not None:
                ids = oriented_ids(ids, corners, view, board.corner_count)
            grid: list[list[float] | None] = [None] * board.corner_count
            for i, corner in zip(ids.tolist(), corners.tolist(), strict=True):
                grid[i] = corner
            frames[str(number_of[frame.index])] = grid
        cameras.append({"frames": frames})
    width, height = run.cameras[0].views.size
    return {"lensmodel": lensmodel, "focal_px": focal_px, "size": [width, height],
            "cols": board.cols, "rows": board.rows, "spacing_m": board.square_m,
            "cameras": cameras}


def _model(camera: dict[str, Any], like: CameraModel) -> CameraModel:
    """mrcal's intrinsics (fx, fy, cx, cy, distortion) as a camera model shaped as ``like``."""
    fx, fy, cx, cy, *distortion = camera["intrinsics"]
    k = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
    return CameraModel(like.width, like.height, k, like.distortion_model,
                       np.asarray(distortion, dtype=np.float64))


def parse_answer(answer: dict[str, Any], truths: list[CameraModel]) -> MrcalResult:
    """:mod:`benchmarks.mrcal_solve`'s answer as camera models (shaped as the truths); an
    error answer raises :class:`MrcalError`."""
    if "error" in answer:
        raise MrcalError(str(answer["error"]))
    cameras = answer["cameras"]
    models = [_model(c, t) for c, t in zip(cameras, truths, strict=True)]
    right_from_left = None
    if len(cameras) == 2:
        rt = np.asarray(cameras[1]["rt_cam_ref"], dtype=np.float64)
        right_from_left = np.eye(4)
        right_from_left[:3, :3] = cv2.Rodrigues(rt[:3])[0]
        right_from_left[:3, 3] = rt[3:]
    return MrcalResult(models, right_from_left, list(answer.get("report", [])))


def run_mrcal(python: Path, run: CalibrationRun, board: Board) -> MrcalResult:
    """mrcal (``mrcal-calibrate-cameras`` under ``python``) on a run's detections, in the
    true lens model (:data:`LENSMODELS`), seeded with the true fx to the nearest 100 px."""
    truths = true_models(run)
    lensmodel = LENSMODELS[truths[0].distortion_model]
    focal_px = nominal_focal_px(truths[0])
    payload = request(run, board, lensmodel=lensmodel, focal_px=focal_px)
    done = subprocess.run([str(python), str(HELPER)], input=json.dumps(payload),
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        last = done.stderr.strip().splitlines()[-1:] or ["no output"]
        raise MrcalError(f"{HELPER.name} exited {done.returncode}: {last[0]}")
    return parse_answer(json.loads(done.stdout), truths)
