"""Camera calibrations as camera_info_manager YAML (``ost.yaml``, ``~/.ros/camera_info``).

The file holds ``image_width``, ``image_height``, ``camera_name``, ``distortion_model`` and
four matrices as ``{rows, cols, data}`` blocks: ``camera_matrix`` (3, 3),
``distortion_coefficients`` (1, N), ``rectification_matrix`` (3, 3) and
``projection_matrix`` (3, 4). They map to :class:`~replay.messages.CameraInfo` ``k``,
``d``, ``r`` and ``p``; the stamp, frame id, binning and ROI are not part of the file.
Numbers are written with ``repr`` so that a save/load round trip is exact.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .atomic import write_text_atomic
from .bounded import read_text, yaml_load
from .errors import OutputError, ReplayError
from .messages import F64, CameraInfo

__all__ = [
    "Calibration",
    "CalibrationFileError",
    "calibration_from_yaml",
    "calibration_to_yaml",
    "load_calibration",
    "save_calibration",
]

#: YAML key -> (rows, cols) of CameraInfo k, d, r, p; cols None = any length (distortion)
_MATRICES: dict[str, tuple[int, int | None]] = {
    "camera_matrix": (3, 3),
    "distortion_coefficients": (1, None),
    "rectification_matrix": (3, 3),
    "projection_matrix": (3, 4),
}


class CalibrationFileError(ReplayError):
    """A calibration file (YAML, or camera_calibration's INI) is missing, unreadable or
    malformed."""


@dataclass(frozen=True)
class Calibration:
    """One camera's calibration file: its ``camera_name`` and model (stamp 0, no frame)."""

    camera_name: str
    camera_info: CameraInfo


def _matrix_block(name: str, value: Any, rows: int, cols: int | None) -> F64:
    if not isinstance(value, dict) or "data" not in value:
        raise CalibrationFileError(f"{name}: expected a block with rows, cols and data")
    try:
        data = np.asarray(value["data"], dtype=np.float64).reshape(-1)
        declared = (int(value.get("rows", rows)), int(value.get("cols", data.size)))
    except (TypeError, ValueError):
        raise CalibrationFileError(f"{name}: data must be a list of numbers") from None
    expected_cols = data.size if cols is None else cols
    if declared != (rows, expected_cols) or data.size != rows * expected_cols:
        raise CalibrationFileError(
            f"{name}: expected {rows}x{expected_cols if cols else 'N'} values, got rows "
            f"{declared[0]}, cols {declared[1]} and {data.size} values"
        )
    return data.reshape(rows, expected_cols) if cols is not None else data


def calibration_from_yaml(text: str) -> Calibration:
    """Parse camera_info_manager YAML text."""
    from ruamel.yaml.error import YAMLError

    try:
        raw = yaml_load(text, "the calibration YAML", CalibrationFileError)
    except YAMLError as err:
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise CalibrationFileError(f"not valid YAML: {first}") from None
    if not isinstance(raw, dict):
        raise CalibrationFileError("expected a mapping of calibration keys")
    missing = [k for k in ("image_width", "image_height", *_MATRICES) if k not in raw]
    if missing:
        raise CalibrationFileError(f"missing {', '.join(missing)}")
    try:
        width, height = int(raw["image_width"]), int(raw["image_height"])
    except (TypeError, ValueError):
        raise CalibrationFileError("image_width and image_height must be integers") from None
    k, d, r, p = (_matrix_block(key, raw[key], rows, cols)
                  for key, (rows, cols) in _MATRICES.items())
    info = CameraInfo(
        stamp_ns=0, frame_id="", width=width, height=height,
        distortion_model=str(raw.get("distortion_model") or "plumb_bob"), d=d, k=k, r=r, p=p,
    )
    return Calibration(str(raw.get("camera_name") or ""), info)


def _block(values: F64, rows: int) -> str:
    data = ", ".join(repr(float(v)) for v in np.asarray(values).reshape(-1))
    cols = np.asarray(values).size // rows
    return f"\n  rows: {rows}\n  cols: {cols}\n  data: [{data}]"


def calibration_to_yaml(info: CameraInfo, *, camera_name: str) -> str:
    """camera_info_manager YAML text of a camera model, in the layout ROS tools write."""
    plain = re.fullmatch(r"[A-Za-z_/][\w./-]*", camera_name) and camera_name.lower() not in (
        "true", "false", "null", "yes", "no", "on", "off")
    name = camera_name if plain else json.dumps(camera_name)
    return (
        f"image_width: {info.width}\n"
        f"image_height: {info.height}\n"
        f"camera_name: {name}\n"
        f"camera_matrix:{_block(info.k, 3)}\n"
        f"distortion_model: {info.distortion_model}\n"
        f"distortion_coefficients:{_block(info.d, 1)}\n"
        f"rectification_matrix:{_block(info.r, 3)}\n"
        f"projection_matrix:{_block(info.p, 3)}\n"
    )


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file; errors name the path."""
    path = Path(path)
    text = read_text(path, CalibrationFileError)
    try:
        return calibration_from_yaml(text)
    except (CalibrationFileError, ValueError) as err:
        raise CalibrationFileError(f"{path}: {err}") from None


def save_calibration(path: str | Path, info: CameraInfo, *, camera_name: str) -> None:
    """Write a calibration file (replaced atomically)."""
    path = Path(path)
    try:
        write_text_atomic(path, calibration_to_yaml(info, camera_name=camera_name))
    except OutputError as err:
        raise CalibrationFileError(str(err)) from None
