"""A moving rig: every camera carried along one smooth path, and where each camera is when.

A scenario's ``[rig_motion]`` table moves the whole rig as a hand-held or robot-mounted rig
moves: a smooth path (a Catmull-Rom spline, continuous velocity) through a random waypoint
every ``segment_s``, each waypoint a translation within ``translation_m`` (x, y, z) and a
turn within ``rotation_rad`` (about x, y, z) of the first camera's optical frame (x right,
y down, z forward) at rest. The cameras keep their places in the rig; the scene stands
still. A camera's camera_info is unchanged; its rendering and its ground-truth target poses
follow it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from replay.geometry import invert, rotation_about
from replay.messages import F64

from .cameras import CameraSpec
from .drift import DriftSpec, world_from_camera_at
from .motion import catmull_rom
from .spec_table import SpecTable

#: the largest turn of a waypoint about one axis, in radians
MAX_ROTATION_RAD = 0.5


@dataclass(frozen=True)
class RigMotionSpec:
    """How the rig moves: a waypoint every ``segment_s`` within ``translation_m`` (3,) and
    ``rotation_rad`` (3,) of its rest pose, along and about the first camera's axes."""

    segment_s: float
    translation_m: F64
    rotation_rad: F64


def parse_rig_motion(table: Any, where: str, source: str) -> RigMotionSpec:
    """Resolve a ``[rig_motion]`` table."""
    f = SpecTable(table, where, source)
    f.text("kind", "smooth", choices=("smooth",))
    spec = RigMotionSpec(segment_s=f.number("segment_s", 0.6, positive=True),
                         translation_m=f.vector("translation_m", 3, [0.0, 0.0, 0.0]),
                         rotation_rad=f.vector("rotation_rad", 3, [0.0, 0.0, 0.0]))
    if np.any(spec.translation_m < 0):
        raise f.fail("translation_m", "ranges must be >= 0")
    if np.any(spec.rotation_rad < 0) or np.any(spec.rotation_rad > MAX_ROTATION_RAD):
        raise f.fail("rotation_rad", f"ranges must be within [0, {MAX_ROTATION_RAD}]")
    f.check_unknown()
    return spec


def _transform(parameters: F64) -> F64:
    """``(4, 4)`` of a translation (3,) then a rotation vector (3,)."""
    out = np.eye(4)
    angle = float(np.linalg.norm(parameters[3:]))
    if angle > 0:
        out[:3, :3] = rotation_about(parameters[3:] / angle, angle)
    out[:3, 3] = parameters[:3]
    return out


@dataclass(frozen=True)
class RigPath:
    """The rig's path: ``rest_from_moved(t)``, the first camera's pose at ``t`` in its rest
    pose's frame, through ``waypoints`` ``(N, 6)`` (translation in m, rotation vector in rad)
    reached every ``segment_s``."""

    segment_s: float
    waypoints: F64

    def rest_from_moved(self, t_s: float) -> F64:
        """``(4, 4)``: where the first camera is at ``t_s`` in its rest frame."""
        return _transform(catmull_rom(self.waypoints, self.segment_s, t_s))


def plan_rig_path(spec: RigMotionSpec, duration_s: float, rng: np.random.Generator) -> RigPath:
    """A random path for ``duration_s``: waypoints drawn uniformly within the ranges."""
    count = math.ceil(duration_s / spec.segment_s) + 2
    ranges = np.concatenate([spec.translation_m, spec.rotation_rad])
    return RigPath(spec.segment_s, rng.uniform(-1.0, 1.0, (count, 6)) * ranges)


@dataclass(frozen=True)
class CameraPoses:
    """Where every camera is at any time: its rest pose in the rig, turned by its drifts
    (:mod:`recorder.drift`), carried along the rig's path (none: the rig stands still)."""

    cameras: tuple[CameraSpec, ...]
    drifts: tuple[DriftSpec, ...] = ()
    path: RigPath | None = None

    @property
    def moving(self) -> bool:
        """Whether the rig moves."""
        return self.path is not None

    def world_from_camera(self, index: int, t_s: float) -> F64:
        """Camera ``index``'s optical frame ``(4, 4)`` in the world at ``t_s``."""
        camera = self.cameras[index]
        pose = world_from_camera_at(camera, self.drifts, t_s)
        if self.path is None:
            return pose
        world_from_rest = self.cameras[0].world_from_camera
        return np.asarray(world_from_rest @ self.path.rest_from_moved(t_s)
                          @ invert(world_from_rest) @ pose, dtype=np.float64)
