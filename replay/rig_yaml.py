"""A calibrated rig's extrinsics as YAML (``rig.yaml``), one block per camera and per pair.

Every pose is ``camera_from_reference``: ``X_camera = R X_reference + t`` with ``X_reference``
in the reference camera's optical frame (the first camera's), ``R`` written both as a matrix
(row-major) and as a rotation vector (axis times angle, rad), ``t`` in metres. The standard
deviations are per axis, of the increments ``R <- exp([d]x) R`` and ``t <- t + dt``. Pairs
give ``second_from_first``'s baseline and rotation angle with their standard deviations.
Numbers are written with ``repr``, lists in flow style: the file is also valid JSON-in-YAML
for any YAML reader.
"""

from __future__ import annotations

import numpy as np

from .geometry import rotation_about
from .messages import F64
from .records import RigSummary

__all__ = ["rig_to_yaml"]


def _list(values: list[float]) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def _matrix(rotation_rad: list[float]) -> F64:
    """Rotation matrix ``(3, 3)`` of a rotation vector."""
    vector = np.asarray(rotation_rad, dtype=np.float64)
    angle = float(np.linalg.norm(vector))
    return rotation_about(vector / angle, angle) if angle > 0 else np.eye(3)


def rig_to_yaml(rig: RigSummary) -> str:
    """``rig.yaml`` text of a rig summary."""
    lines = [f"convention: {rig.convention}  # X_camera = R X_reference + t",
             f"reference: {rig.reference}", "cameras:"]
    for camera in rig.cameras:
        matrix = _matrix(camera.rotation_rad)
        lines += [
            f"  - namespace: {camera.namespace}",
            f"    frame_id: {camera.frame_id}",
            f"    rotation_matrix: {_list(matrix.reshape(-1).tolist())}",
            f"    rotation_vector_rad: {_list(camera.rotation_rad)}",
            f"    rotation_std_rad: {_list(camera.rotation_std_rad)}",
            f"    translation_m: {_list(camera.translation_m)}",
            f"    translation_std_m: {_list(camera.translation_std_m)}",
        ]
    lines.append("pairs:" if rig.pairs else "pairs: []")
    for pair in rig.pairs:
        lines += [
            f"  - first: {pair.first}",
            f"    second: {pair.second}",
            f"    joint_views: {pair.joint_views}",
            f"    baseline_m: {pair.baseline_m!r}",
            f"    baseline_std_m: {pair.baseline_std_m!r}",
            f"    rotation_deg: {pair.rotation_deg!r}",
            f"    rotation_std_deg: {pair.rotation_std_deg!r}",
            f"    epipolar_rms_px: {pair.epipolar_rms_px!r}",
        ]
    return "\n".join(lines) + "\n"
