"""Calibrate cameras from a log: detect, solve, summarise, write the evidence and report.

The steps are plain functions from value to value: :func:`~.views.detect_views` (the pass
over the log), :func:`~.solving.solve_rig` (every camera, the rig and every board pose at once),
:func:`~.statistics.camera_statistics` (what the solution says of its own accuracy),
:func:`~.summary.build_summary`, :func:`~.evidence.write_evidence` (the second pass, which
copies the log) and :func:`~.report.write_files`. With the report, a short log's statistics
are computed on a thread of their own while the evidence pass runs, and joined right after it
(:func:`_write_report`): their error is raised there. Every output is written into a hidden
temporary folder and moved into place only when all of it succeeded.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from processors.calibration.board import Board
from processors.calibration.corners import remeasures
from processors.calibration.joint import JointResult
from processors.calibration.options import CalibrationOptions
from replay.atomic import AtomicFolder
from replay.formats import LogReader, open_reader, open_writer
from replay.formats.background import BackgroundWriter
from replay.records import CalibrationSummary, Scenario, ScenarioCamera
from replay.storage import Location, local_paths

from ..errors import CalibrationError, InputError, UsageError
from ..processing.cameras import cameras_in, find_camera
from ..requests.calibrate import CalibrateRequest
from ..requests.fields import RequestError
from .evidence import EVIDENCE_ZSTD_LEVEL, write_evidence, write_summary
from .instants import ViewsOfRig
from .remeasure import remeasured_rig
from .report import output_names, write_files
from .solving import CalibratedCamera, RigSolution, guiding_models, solve_rig
from .statistics import CameraStatistics, beside_the_pass, camera_statistics
from .summary import build_summary
from .views import CameraViews, LogViews, detect_views, with_speed_limit

__all__ = ["CalibrationRun", "MeasureAgain", "calibrate_log", "cameras_of"]

#: the views' corners given again after a first solve: (every camera's views, the rig's views,
#: the first solve) -> the rig's views with new corners
MeasureAgain = Callable[[list[CameraViews], ViewsOfRig, JointResult], ViewsOfRig]


@dataclass(frozen=True)
class CalibrationRun:
    """Everything :func:`calibrate_log` computed and where it wrote it."""

    solved: RigSolution
    statistics: list[CameraStatistics]  # per camera, in camera order
    output_dir: Path
    files: list[Path]
    wall_s: float
    summary: CalibrationSummary
    warnings: list[str]  # what the user should know, e.g. frames that did not decode

    @property
    def cameras(self) -> list[CalibratedCamera]:
        """The calibrated cameras, in the order named."""
        return self.solved.cameras


def _check_size(views: CameraViews) -> None:
    """The images must have the size the log's camera_info says."""
    info = views.log_info
    if info is not None and info.width and info.height and \
            (info.width, info.height) != views.size:
        raise InputError(
            f"{views.source.image_topic} images are {views.size[0]}x{views.size[1]} but "
            f"{views.source.info_topic} says {info.width}x{info.height}")


def _checked(found: LogViews, max_speed_px: float | None) -> list[CameraViews]:
    """Every camera's views, their image size checked, past the speed limit if one is set."""
    out = []
    for detected in found.cameras:
        _check_size(detected)
        out.append(detected if max_speed_px is None else with_speed_limit(detected,
                                                                          max_speed_px))
    return out


def _namespaces(log: Location, cameras: list[str], *, recover: bool) -> list[str]:
    """The namespaces of cameras named by namespace or image topic (a rig's file names)."""
    with open_reader(log, recover=recover) as reader:
        spaces = [find_camera(reader, ns).namespace for ns in cameras]
    if len(set(spaces)) != len(spaces):
        raise UsageError(f"a camera is named twice: {', '.join(cameras)}")
    return spaces


def _write_report(reader: LogReader, folder: Path, solved: RigSolution, *, board: Board,
                  options: CalibrationOptions, scenario: Scenario | None,
                  camera_name: str | None, progress: bool | None
                  ) -> tuple[CalibrationSummary, list[CameraStatistics]]:
    """calibration.mcap, the calibration files, the figures and report.md into ``folder``;
    the summary they show and the statistics it holds.

    calibration.mcap is compressed and written on a thread of its own while this one
    annotates the frames; a short log's statistics are computed on another one meanwhile
    (:func:`~.statistics.beside_the_pass`) and joined when the pass is done, a long log's
    then. The log is complete, or its error raised, when this returns."""
    with BackgroundWriter(partial(open_writer, folder / "calibration.mcap",
                                  compression_level=EVIDENCE_ZSTD_LEVEL)) as log:
        # leaving the pool waits for its thread, the pass's error first
        with ThreadPoolExecutor(max_workers=1, thread_name_prefix="camlog-statistics") as pool:
            beside = pool.submit(_statistics, solved, board) if beside_the_pass(solved) \
                else None
            evidence = write_evidence(reader, log, solved, board=board, progress=progress)
        statistics = beside.result() if beside is not None else _statistics(solved, board)
        summary = build_summary(solved, statistics, board=board, options=options,
                                scenario=scenario)
        write_summary(log, summary, log_time_ns=reader.end_ns or 0)
        write_files(folder, solved, statistics, summary=summary, evidence=evidence,
                    camera_name=camera_name)
    return summary, statistics


def _statistics(solved: RigSolution, board: Board) -> list[CameraStatistics]:
    """Each camera's statistics (:func:`~.statistics.camera_statistics`); singular
    equations as one line."""
    with _singular_is_one_line():
        return camera_statistics(solved, points_in_board=board.points_in_board())


def cameras_of(request: CalibrateRequest) -> list[str]:
    """The cameras a request names, or the log's only camera (its raw images first: processed
    images, masks or edges, are cameras of their own)."""
    named = request.named_cameras
    if named:
        return named
    with open_reader(request.log, recover=request.recover) as reader:
        cameras = cameras_in(reader)
    raw = {namespace for namespace, topic in cameras if "/image_raw" in topic}
    spaces = sorted(raw or {namespace for namespace, _topic in cameras})
    if len(spaces) != 1:
        found = f"{request.log}: {', '.join(spaces) or 'none'}".replace("{", "{{").replace(
            "}", "}}")
        raise RequestError(CalibrateRequest, "name the camera with {camera} (or "
                                             "{left}/{right}); camera namespaces in " + found)
    return spaces


@contextmanager
def _singular_is_one_line() -> Iterator[None]:
    """Equations the views leave singular, should a solve meet them, as one CalibrationError
    line rather than numpy's traceback."""
    try:
        yield
    except np.linalg.LinAlgError as err:
        raise CalibrationError(
            f"the views leave the calibration's equations singular ({err}): some unknown "
            "is not held by them (e.g. every view of a camera shows the board alike)"
            ) from None


def calibrate_log(request: CalibrateRequest, *, workers: int | None = None,
                  measure_again: MeasureAgain | None = None) -> CalibrationRun:
    """Calibrate one camera, a stereo pair (``left``/``right``) or, with ``rig`` or three
    cameras or more, a rig (every camera's file named after its namespace, and rig.yaml with
    every camera's pose relative to the first); a circle grid's circles are ``diameter``
    across (None: measured in the images); without ``report`` only the calibration files and
    calibration.json are written (no second pass over the log, no figures).
    ``measure_again`` gives the views' corners again after a first solve, which is then
    solved again (default: measured on the board plane where
    :func:`~processors.calibration.corners.remeasures` says; an analysis may give, for
    instance, ideal corners)."""
    board, options = request.board(), request.options()
    cameras = cameras_of(request)
    log, output_dir, recover = request.log, request.output_dir, request.recover
    progress, report = request.progress, request.report
    approximate_s, camera_name = request.approximate, request.camera_name
    max_speed_px, diameter_m = request.max_chessboard_speed, request.diameter
    started = time.perf_counter()
    as_rig = len(cameras) > 2 or (request.is_rig and len(cameras) > 1)
    stereo_mode = len(cameras) == 2 and not as_rig
    with AtomicFolder(output_dir, output_names(stereo_mode, report=report,
                                               rig=_namespaces(log, cameras, recover=recover)
                                               if as_rig else None),
                      overwrite=request.overwrite, inputs=local_paths(log)) as staged, \
            open_reader(log, recover=recover) as reader:
        if reader.message_count == 0:
            raise InputError(f"{log} is empty (no messages)")
        sources = [find_camera(reader, ns) for ns in cameras]
        workers = workers or os.cpu_count() or 2
        found = detect_views(reader, sources, board, workers=workers, progress=progress)
        cameras_views = _checked(found, max_speed_px)
        if board.pattern == "charuco":
            # a first calibration places the corners a second detection refines (see
            # processors.calibration.targets): more of them, and nearer the border
            with _singular_is_one_line():
                models = guiding_models(cameras_views, board, options,
                                        approximate_s=approximate_s)
            if models:
                found = detect_views(reader, sources, board, workers=workers,
                                     progress=progress, models=models)
                cameras_views = _checked(found, max_speed_px)
        # a fisheye's chessboard corners and every ChArUco corner are measured again through
        # a first solution (see .remeasure)
        remeasure: Callable[[ViewsOfRig, JointResult], ViewsOfRig] | None = None
        if measure_again is not None:
            remeasure = partial(measure_again, cameras_views)
        elif remeasures(board, options.distortion_model):
            remeasure = partial(remeasured_rig, reader, cameras_views, board=board,
                                workers=workers, progress=progress)
        scenario = found.scenario
        with _singular_is_one_line():
            solved = solve_rig(cameras_views, board, options, approximate_s=approximate_s,
                               diameter_m=diameter_m, remeasure=remeasure, as_rig=as_rig,
                               truth=_truth(scenario, cameras_views))
        if report:
            summary, statistics = _write_report(
                reader, staged.path, solved, board=board, options=options, scenario=scenario,
                camera_name=camera_name, progress=progress)
        else:
            statistics = _statistics(solved, board)
            summary = build_summary(solved, statistics, board=board, options=options,
                                    scenario=scenario)
            write_files(staged.path, solved, statistics, summary=summary, evidence=None,
                        camera_name=camera_name)
    diameter_warning = solved.circles.warning() if solved.circles is not None else None
    return CalibrationRun(solved, statistics, output_dir, staged.files,
                          time.perf_counter() - started, summary,
                          [*reader.warnings, *found.warnings,
                           *([diameter_warning] if diameter_warning else [])])


def _truth(scenario: Scenario | None, cameras: list[CameraViews]
           ) -> list[ScenarioCamera | None] | None:
    """Each camera's simulator record, in a simulated log (None otherwise)."""
    if scenario is None:
        return None
    return [scenario.camera_for(c.source.namespace,
                                c.log_info.frame_id if c.log_info else None) for c in cameras]
