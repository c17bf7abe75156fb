"""``camlog calibrate --check``: measure an existing calibration on a log's board views."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from processors.calibration.board import Board
from processors.calibration.check import linearity_error, reprojection_rms
from processors.calibration.stereo import epipolar_errors, orient_right_views
from replay.calibration_yaml import load_calibration
from replay.camera import CameraModel
from replay.formats import open_reader

from ..errors import CalibrationError, InputError, UsageError
from .instants import stereo_pairs
from .views import detect_views, resolve_camera, size_hint


@dataclass
class CheckResult:
    """Per-view figures of merit of a calibration on a log."""

    views: int
    linearity_px: list[float]  # per view (mono: the one camera; stereo: the left camera)
    reprojection_px: list[float]
    epipolar_px: list[float]  # stereo only

    def lines(self) -> list[str]:
        """One line per figure: mean, median and max over the views."""

        def stats(name: str, values: list[float]) -> str:
            a = np.asarray(values)
            return (f"{name}: mean {a.mean():.4f} px, median {np.median(a):.4f} px, "
                    f"max {a.max():.4f} px over {a.size} views")

        out = [stats("linearity error", self.linearity_px),
               stats("reprojection RMS", self.reprojection_px)]
        if self.epipolar_px:
            out.append(stats("epipolar error", self.epipolar_px))
        return out


def check_log(log: Path, *, board: Board, cameras: list[str], calibrations: list[Path],
              approximate_s: float | None = None, progress: bool | None = None,
              recover: bool = False) -> CheckResult:
    """Linearity and reprojection error per view (mono), plus epipolar error (stereo)."""
    if len(calibrations) != len(cameras):
        raise UsageError(f"give one --calibration per camera ({len(cameras)}), "
                         f"got {len(calibrations)}")
    infos = [load_calibration(p).camera_info for p in calibrations]
    with open_reader(log, recover=recover) as reader:
        sources = [resolve_camera(reader, ns) for ns in cameras]
        streams = detect_views(reader, sources, board, workers=os.cpu_count() or 2,
                               progress=progress).cameras
    models = []
    for stream, info, path in zip(streams, infos, calibrations, strict=True):
        if stream.size != (info.width, info.height):
            raise InputError(f"{path} is for {info.width}x{info.height} images, "
                             f"{stream.source.image_topic} has "
                             f"{stream.size[0]}x{stream.size[1]}")
        models.append(CameraModel.from_camera_info(info))
    candidates = [f.index for f in streams[0].frames if f.candidate]
    if not candidates:
        raise CalibrationError(f"no {board.cols}x{board.rows} board found in "
                               f"{streams[0].source.image_topic}{size_hint(streams[0], board)}")
    first = [streams[0].detection(i) for i in candidates]
    # rows are straight lines only where a view shows them whole
    linear = [linearity_error(d.corners_px, models[0], board) for d in first
              if len(d.ids) == board.corner_count] or [float("nan")]
    reproj = [reprojection_rms(d.corners_px, models[0], board, d.ids) for d in first]
    epipolar: list[float] = []
    if len(streams) == 2:
        left, right = streams
        pairs = [(li, ri) for li, ri in stereo_pairs(left, right, approximate_s)
                 if left.frames[li].candidate and right.frames[ri].candidate
                 and np.array_equal(left.detection(li).ids, right.detection(ri).ids)]
        if not pairs:
            raise CalibrationError("no stereo pair shows the whole board in both cameras")
        left_views = [left.corners(li) for li, _ in pairs]
        right_views = orient_right_views(
            board.points_in_board(), left_views, [right.corners(ri) for _, ri in pairs],
            left_model=models[0], right_model=models[1])
        epipolar = epipolar_errors(left_views, right_views, left_model=models[0],
                                   right_model=models[1], r1=infos[0].r, p1=infos[0].p,
                                   r2=infos[1].r, p2=infos[1].p)
    return CheckResult(len(first), linear, reproj, epipolar)
