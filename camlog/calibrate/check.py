"""``camlog calibrate --check``: measure an existing calibration on a log's board views."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from processors.calibration.holds import Seen
from processors.calibration.stereo import epipolar_errors, orient_right_views
from processors.calibration.view_fit import ViewFit, fit_view, linearity_error
from replay.calibration_yaml import load_calibration
from replay.camera import CameraModel
from replay.formats import open_reader
from replay.messages import F64

from ..errors import CalibrationError, InputError, UsageError
from ..processing.cameras import find_camera
from ..requests.calibrate import CalibrateRequest
from .circles import CircleSize, circle_size
from .flow import cameras_of
from .instants import stereo_pairs
from .views import CameraViews, detect_views, size_hint


@dataclass
class CheckResult:
    """Per-view figures of merit of a calibration on a log."""

    views: int
    linearity_px: list[float]  # per view (mono: the one camera; stereo: the left camera)
    reprojection_px: list[float]
    epipolar_px: list[float]  # stereo only
    circles: CircleSize | None = None  # a circle grid's circles, as modelled

    def lines(self) -> list[str]:
        """One line per figure: mean, median and max over the views."""

        def stats(name: str, values: list[float]) -> str:
            a = np.asarray(values)
            return (f"{name}: mean {a.mean():.4f} px, median {np.median(a):.4f} px, "
                    f"max {a.max():.4f} px over {a.size} views")

        out = [f"circle diameter {self.circles.describe()}"] if self.circles else []
        out += [stats("linearity error", self.linearity_px),
                stats("reprojection RMS", self.reprojection_px)]
        if self.epipolar_px:
            out.append(stats("epipolar error", self.epipolar_px))
        return out


def measure_calibration(request: CalibrateRequest) -> CheckResult:
    """Linearity and reprojection error per view (mono), plus epipolar error (stereo), of the
    request's ``calibration`` files on its log.

    A circle grid's detections are the centroids of its discs' images, as in ``calibrate``:
    the circles are ``diameter_m`` across (None: as the images measure them), the
    reprojection compares the detections with the discs' centroids, and the rows and the
    epipolar lines are those of the circles' centres (the detections moved by the disc
    shift at each view's fitted pose)."""
    board, cameras = request.board(), cameras_of(request)
    log, calibrations, recover = request.log, list(request.calibration), request.recover
    approximate_s, diameter_m, progress = request.approximate, request.diameter, request.progress
    if len(calibrations) != len(cameras):
        raise UsageError(f"give one --calibration per camera ({len(cameras)}), "
                         f"got {len(calibrations)}")
    infos = [load_calibration(p).camera_info for p in calibrations]
    with open_reader(log, recover=recover) as reader:
        sources = [find_camera(reader, ns) for ns in cameras]
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
    circles = circle_size(streams, board, diameter_m)
    disc_m = circles.diameter_m if circles is not None else None
    points = board.points_in_board()
    first = [streams[0].detection(i) for i in candidates]
    fits = [fit_view(d.corners_px, models[0], points[d.ids], disc_diameter_m=disc_m)
            for d in first]
    # rows are straight lines only where a view shows them whole
    linear = [linearity_error(_centres(d.corners_px, f), models[0], board)
              for d, f in zip(first, fits, strict=True)
              if len(d.ids) == board.corner_count] or [float("nan")]
    reproj = [float("nan") if f is None else f.rms_px for f in fits]
    epipolar: list[float] = []
    if len(streams) == 2:
        left, right = streams
        pairs = [(li, ri) for li, ri in stereo_pairs(left, right, approximate_s)
                 if left.frames[li].candidate and right.frames[ri].candidate
                 and np.array_equal(left.detection(li).ids, right.detection(ri).ids)]
        if not pairs:
            raise CalibrationError("no stereo pair shows the whole board in both cameras")
        right_views = [seen.corners_px for seen in orient_right_views(
            points, [_seen(left, li) for li, _ in pairs], [_seen(right, ri) for _, ri in pairs],
            left_model=models[0], right_model=models[1])]
        fit_of = dict(zip(candidates, fits, strict=True))
        left_centres = [_centres(left.corners(li), fit_of[li]) for li, _ in pairs]
        right_centres = [
            _centres(c, fit_view(c, models[1], points[left.detection(li).ids],
                                 disc_diameter_m=disc_m))
            for c, (li, _) in zip(right_views, pairs, strict=True)]
        epipolar = epipolar_errors(left_centres, right_centres, left_model=models[0],
                                   right_model=models[1], r1=infos[0].r, p1=infos[0].p,
                                   r2=infos[1].r, p2=infos[1].p)
    return CheckResult(len(first), linear, reproj, epipolar, circles)


def _seen(views: CameraViews, index: int) -> Seen:
    detection = views.detection(index)
    return Seen(detection.ids, detection.corners_px)


def _centres(corners_px: F64, fit: ViewFit | None) -> F64:
    """Where a view shows the points themselves: a circle grid's detections moved by the
    disc shift at the view's fitted pose (the detections when no pose was found)."""
    return corners_px if fit is None else fit.centres_px
