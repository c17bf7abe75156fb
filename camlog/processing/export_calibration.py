"""Camera models out of a rerun recording: ``camlog export REC.rrd --calibration -o DIR``.

``camlog view`` logs every camera's camera_info in full beside its ``Pinhole``
(:mod:`rerun_export.camera_records`). This reads them back and writes one
camera_info_manager YAML file per camera (``world/stereo/left`` -> ``stereo_left.yaml``,
camera name ``stereo/left``), every number as the log held it; a camera of several
recordings in one file gets ``_2``, ``_3``... The files appear together (a temporary folder
moved into place), or not at all.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from replay.atomic import AtomicFolder
from replay.calibration_yaml import calibration_to_yaml
from replay.lens_models import LENS_MODELS, canonical_name
from replay.messages import CameraInfo
from replay.storage import local_paths

from ..calibrate.report import camera_file_stem
from ..errors import InputError, UsageError
from ..requests.logs import ExportRequest

__all__ = ["CalibrationExport", "ExportedCamera", "export_calibration"]


@dataclass(frozen=True)
class ExportedCamera:
    """One calibration file: the camera's entity, the file, how many different models the
    recording logged for it (the file holds the last)."""

    entity: str
    path: Path
    models: int


@dataclass(frozen=True)
class CalibrationExport:
    """The calibration files written into ``output``."""

    output: Path
    cameras: list[ExportedCamera]


def _ros_model(info: CameraInfo) -> CameraInfo:
    """``info`` with its lens model named as ROS names it (``kannala_brandt`` and ``fisheye``
    -> ``equidistant``, empty -> ``plumb_bob``); a model camlog does not know keeps its name."""
    name = canonical_name(info.distortion_model)
    return replace(info, distortion_model=name) if name in LENS_MODELS else info


def export_calibration(request: ExportRequest) -> CalibrationExport:
    """Write every camera model of the recording ``request.log`` as a calibration file into
    ``request.output``."""
    from rerun_export.camera_records import recorded_cameras
    from rerun_export.errors import RerunExportError

    paths = local_paths(request.log)
    if len(paths) != 1 or paths[0].suffix != ".rrd":
        raise UsageError(f"--calibration reads a rerun recording (.rrd), not {request.log}")
    (path,) = paths
    if not path.is_file():
        raise InputError(f"{path} does not exist")
    try:
        cameras = recorded_cameras(path)
    except RerunExportError as err:
        raise InputError(str(err)) from None
    if not cameras:
        raise InputError(f"{path} holds no camera model (a CameraInfo beside a Pinhole, as "
                         "camlog view logs them)")
    names: list[str] = []
    for camera in cameras:
        stem = camera_file_stem(camera.entity.removeprefix("/").removeprefix("world/"))
        name, n = f"{stem}.yaml", 1
        while name in names:
            n += 1
            name = f"{stem}_{n}.yaml"
        names.append(name)
    output = request.output
    with AtomicFolder(output, names, overwrite=request.overwrite, inputs=[path]) as folder:
        for camera, name in zip(cameras, names, strict=True):
            camera_name = camera.entity.removeprefix("/").removeprefix("world/")
            (folder.path / name).write_text(calibration_to_yaml(_ros_model(camera.info),
                                                                camera_name=camera_name))
    return CalibrationExport(output, [
        ExportedCamera(camera.entity, output / name, camera.models)
        for camera, name in zip(cameras, names, strict=True)])
