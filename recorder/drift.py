"""Calibration drift: a camera turned by a small angle from some moment of a recording on.

A scenario's ``[[drifts]]`` tables (or ``camlog record --drift CAMERA:AXIS:DEGREES@SECONDS``)
each turn one camera about an axis of its own optical frame (x right, y down, z forward):
``roll`` about z, ``pitch`` about x, ``yaw`` about y, by ``degrees`` (right-handed), from
``start_s`` after the recording's start. The camera's camera_info keeps the calibration it
started with; its rendering and its ground-truth target poses follow the turned camera.
Drifts of one camera compose in the order they start, each about the axes of the camera as
the earlier ones left it: ``world_from_camera(t) = world_from_camera @ R_1 @ R_2 ...``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from replay.geometry import rotation_about
from replay.messages import F64

from .cameras import CameraSpec, named_camera
from .spec_table import SpecTable

#: drift axis -> the optical-frame axis it turns about
AXES: dict[str, tuple[float, float, float]] = {
    "roll": (0.0, 0.0, 1.0), "pitch": (1.0, 0.0, 0.0), "yaw": (0.0, 1.0, 0.0)}
#: the largest drift a scenario accepts, in degrees
MAX_DEGREES = 45.0


@dataclass(frozen=True)
class DriftSpec:
    """One camera (by name) turned by ``degrees`` about ``axis`` from ``start_s`` on."""

    camera: str
    axis: str
    degrees: float
    start_s: float

    def camera_from_drifted(self) -> F64:
        """The rotation ``(3, 3)`` from the turned optical frame to the calibrated one."""
        return rotation_about(np.asarray(AXES[self.axis]), math.radians(self.degrees))


def parse_drift(table: Any, where: str, source: str,
                cameras: Sequence[CameraSpec]) -> DriftSpec:
    """Resolve one ``[[drifts]]`` table; ``camera`` is a camera's name or namespace."""
    f = SpecTable(table, where, source)
    drift = DriftSpec(camera=named_camera(f, cameras), axis=f.text("axis", choices=tuple(AXES)),
                      degrees=f.number("degrees", low=-MAX_DEGREES, high=MAX_DEGREES),
                      start_s=f.number("start_s", 0.0, low=0.0))
    f.check_unknown()
    return drift


def world_from_camera_at(camera: CameraSpec, drifts: Sequence[DriftSpec], t_s: float) -> F64:
    """The camera's optical frame ``(4, 4)`` in the world at ``t_s`` after the start, with
    every drift of it that has started by then."""
    pose = np.array(camera.world_from_camera, dtype=np.float64)
    for drift in sorted(drifts, key=lambda d: d.start_s):
        if drift.camera == camera.name and t_s >= drift.start_s:
            pose[:3, :3] = pose[:3, :3] @ drift.camera_from_drifted()
    return pose
