"""What ``camlog calibrate`` writes besides the log: YAML, INI, JSON, figures and Markdown."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from camlog.calibrate.figures import (
    coverage_figure,
    rectified_pair_figure,
    residual_figure,
    uncertainty_figure,
    view_error_figure,
)
from replay.calibration_ini import ost_text
from replay.calibration_yaml import calibration_to_yaml
from replay.records import CalibrationSummary
from replay.rig_yaml import rig_to_yaml

from .evidence import Evidence
from .markdown import markdown_report
from .solving import CalibratedCamera, RigSolution
from .statistics import CameraStatistics

__all__ = ["FIGURES", "camera_file_stem", "output_names", "write_files"]

#: figures drawn per camera (stereo: prefixed ``left_`` / ``right_``)
FIGURES = ("coverage.png", "view_errors.png", "residuals.png", "uncertainty.png")


def camera_file_stem(namespace: str) -> str:
    """A rig camera's file names start with its namespace, slashes made underscores
    (``/rig/left`` -> ``rig_left``)."""
    return namespace.strip("/").replace("/", "_") or "camera"


def output_names(stereo: bool, *, report: bool = True, rig: list[str] | None = None
                 ) -> list[str]:
    """Every file a calibration writes into its output folder (``report``: with the
    annotated log, figures and Markdown report; ``rig``: the namespaces of a rig's cameras,
    calibrated as a rig)."""
    if rig is not None:
        stems = [camera_file_stem(ns) for ns in rig]
        files = [*(f"{stem}.yaml" for stem in stems), "rig.yaml", "calibration.json"]
        if not report:
            return files
        return [*files, *(f"{stem}_{f}" for stem in stems for f in FIGURES),
                "calibration.mcap", "report.md"]
    calibrations = ["left.yaml", "right.yaml"] if stereo else ["ost.yaml"]
    if not report:
        return [*calibrations, "ost.txt", "calibration.json"]
    per_camera = [f"{side}_{f}" for side in ("left", "right") for f in FIGURES] if stereo \
        else list(FIGURES)
    pair = ["rectified.png"] if stereo else []
    return [*calibrations, *pair, *per_camera, "ost.txt", "calibration.mcap", "report.md",
            "calibration.json"]


def _figures(folder: Path, solved: RigSolution, camera: CalibratedCamera,
             statistics: CameraStatistics, prefix: str) -> list[str]:
    """The camera's coverage, per-view error, residual and uncertainty figures; their file
    names."""
    size, namespace, joint = camera.views.size, camera.views.source.namespace, solved.joint
    used, rejected = solved.used_corners(camera), solved.rejected_corners(camera)
    # views are not judged by their RMS (outliers are single corners): no limit line
    order = sorted(camera.view_ids, key=solved.first_frame)
    uncertainty = statistics.uncertainty
    figures = {
        "coverage.png": coverage_figure(
            size, used, rejected,
            f"{namespace}: {len(used)} views used, {len(rejected)} rejected",
            camera.coverage.bars()),
        "view_errors.png": view_error_figure(
            [0.0 if v in joint.rejected else joint.view_rms_px(v) for v in order],
            [v in joint.rejected for v in order], None,
            f"{namespace}: per-view reprojection error"),
        "residuals.png": residual_figure(
            size, used, [joint.residuals_px[v] for v in solved.used_views(camera)],
            f"{namespace}: residuals (observed - projected)"),
        "uncertainty.png": uncertainty_figure(
            size, uncertainty.pixels, uncertainty.sigma_px,
            f"{namespace}: projection uncertainty (1 sigma) at "
            f"{uncertainty.range_m:.2f} m: median "
            f"{uncertainty.median_px:.3f} px, worst "
            f"{uncertainty.worst_px:.3f} px",
            np.concatenate(used) if used else None),
    }
    for name, image in figures.items():
        cv2.imwrite(str(folder / f"{prefix}{name}"), image)
    return [f"{prefix}{name}" for name in figures]


def _write_rig(folder: Path, solved: RigSolution, statistics: list[CameraStatistics], *,
               summary: CalibrationSummary, evidence: Evidence | None,
               camera_name: str | None) -> list[str]:
    """A rig's files: one calibration per camera, named after its namespace, and rig.yaml;
    with the ``evidence`` its figures' names."""
    assert summary.rig is not None
    figures: list[str] = []
    for camera, camera_statistics in zip(solved.cameras, statistics, strict=True):
        source = camera.views.source
        stem = camera_file_stem(source.namespace)
        name = f"{camera_name}/{source.name}" if camera_name else source.name
        (folder / f"{stem}.yaml").write_text(calibration_to_yaml(camera.camera_info,
                                                                 camera_name=name))
        if evidence is not None:
            figures += _figures(folder, solved, camera, camera_statistics, f"{stem}_")
    (folder / "rig.yaml").write_text(rig_to_yaml(summary.rig))
    return figures


def _write_camera_calibration(folder: Path, solved: RigSolution,
                              statistics: list[CameraStatistics], *, evidence: Evidence | None,
                              camera_name: str | None) -> list[str]:
    """A mono camera's or a stereo pair's files (camera_calibration's names); with the
    ``evidence`` its figures' names."""
    figures: list[str] = []
    cameras, stereo = solved.cameras, solved.stereo
    for index, (camera, camera_statistics) in enumerate(zip(cameras, statistics, strict=True)):
        side = "left" if index == 0 else "right"
        name = camera_name or camera.views.source.name
        if stereo is not None:
            name = f"{camera_name}/{side}" if camera_name else camera.views.source.name
        yaml_name = "ost.yaml" if stereo is None else f"{side}.yaml"
        (folder / yaml_name).write_text(calibration_to_yaml(camera.camera_info,
                                                            camera_name=name))
        if evidence is not None:
            figures += _figures(folder, solved, camera, camera_statistics,
                                "" if stereo is None else f"{side}_")
    if stereo is not None:
        left, right = cameras
        (folder / "ost.txt").write_text(ost_text(left=left.camera_info,
                                                 right=right.camera_info))
        if evidence is not None and evidence.rectified_pair is not None:
            cv2.imwrite(str(folder / "rectified.png"), rectified_pair_figure(
                *evidence.rectified_pair,
                f"rectified pair: epipolar RMS {stereo.epipolar_rms_px:.3f} px"))
            figures.append("rectified.png")
    else:
        (folder / "ost.txt").write_text(ost_text(cameras[0].camera_info))
    return figures


def write_files(folder: Path, solved: RigSolution, statistics: list[CameraStatistics], *,
                summary: CalibrationSummary, evidence: Evidence | None,
                camera_name: str | None) -> None:
    """Calibration files and the JSON summary into ``folder``, and with the ``evidence``
    pass's results the figures (with each camera's ``statistics``) and the Markdown
    report."""
    if summary.rig is not None:
        figures = _write_rig(folder, solved, statistics, summary=summary, evidence=evidence,
                             camera_name=camera_name)
    else:
        figures = _write_camera_calibration(folder, solved, statistics, evidence=evidence,
                                            camera_name=camera_name)
    (folder / "calibration.json").write_text(summary.to_json_text(indent=1) + "\n")
    if evidence is not None:
        (folder / "report.md").write_text(markdown_report(summary, figures))
