"""Target trajectories: a pose for every instant, planned up front from the seed."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from replay.geometry import invert, rotation_about
from replay.messages import F64

from .cameras import CameraSpec
from .errors import ScenarioError
from .target_spec import TargetSpec
from .targets import center_in_target, outline_in_target

#: a fully visible board keeps this margin (px at 640 px width, scaled with the width) from
#: the image border: the calibration's detector drops corners within 8 px of it
IN_VIEW_MARGIN_PX = 8.0
REFERENCE_WIDTH_PX = 640
MAX_TRIES = 5000


@dataclass(frozen=True)
class Trajectory:
    """Piecewise-constant poses: ``world_from_target[i]`` holds for ``[i * hold_s, ...)``."""

    hold_s: float
    world_from_target: F64  # (N, 4, 4)

    def at(self, t_s: float) -> F64:
        """``world_from_target`` (4, 4) at time ``t_s`` (the pose held then)."""
        index = min(math.floor(max(t_s, 0.0) / self.hold_s), len(self.world_from_target) - 1)
        pose: F64 = self.world_from_target[index]
        return pose


def visible_fraction(
    world_from_target: F64, points_in_target: F64, cameras: tuple[CameraSpec, ...],
    margin_px: float = IN_VIEW_MARGIN_PX,
) -> float:
    """Smallest fraction, over cameras, of the points that project inside the image, at
    least ``margin_px`` (scaled to a 640 px wide image) from its border."""
    worst = 1.0
    for camera in cameras:
        margin = margin_px * min(1.0, camera.model.width / REFERENCE_WIDTH_PX)
        camera_from_target = invert(camera.world_from_camera) @ world_from_target
        pts = points_in_target @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
        if np.any(pts[:, 2] <= 0.01):
            return 0.0
        uv = camera.model.project(pts)
        w, h = camera.model.width, camera.model.height
        inside = (
            (uv[:, 0] >= margin) & (uv[:, 0] <= w - 1 - margin)
            & (uv[:, 1] >= margin) & (uv[:, 1] <= h - 1 - margin)
        )
        worst = min(worst, float(np.mean(inside)))
    return worst


def _random_pose(target: TargetSpec, rng: np.random.Generator) -> F64:
    motion = target.motion
    center = motion.center_m + np.array([
        rng.uniform(-motion.xy_range_m, motion.xy_range_m),
        rng.uniform(-motion.xy_range_m, motion.xy_range_m),
        0.0,
    ])
    center[2] = rng.uniform(*motion.z_range_m)
    # Face up (target z down, towards the ground), random yaw, then tilt about a random
    # horizontal axis.
    face_up = np.diag([1.0, -1.0, -1.0])
    yaw = rotation_about(np.array([0.0, 0.0, 1.0]), rng.uniform(-math.pi, math.pi))
    axis_angle = rng.uniform(0, 2 * math.pi)
    tilt = rotation_about(np.array([math.cos(axis_angle), math.sin(axis_angle), 0.0]),
                          motion.max_tilt_rad * math.sqrt(rng.uniform(0, 1)))
    rotation = tilt @ yaw @ face_up
    pose = np.eye(4)
    pose[:3, :3] = rotation
    offset = center_in_target(target)
    pose[:3, 3] = center - rotation @ offset
    return pose


def plan_trajectory(
    target: TargetSpec, cameras: tuple[CameraSpec, ...], duration_s: float,
    rng: np.random.Generator,
) -> Trajectory:
    """Poses for ``duration_s``; random poses are fully in view of every camera, except
    a ``partial_view_probability`` share that are deliberately cut by the image border."""
    motion = target.motion
    if motion.kind == "static":
        return Trajectory(duration_s + 1.0, motion.world_from_target[None])
    outline = outline_in_target(target)
    count = math.ceil(duration_s / motion.hold_s) + 1
    poses = []
    for _ in range(count):
        partial = rng.uniform() < motion.partial_view_probability
        for _try in range(MAX_TRIES):
            pose = _random_pose(target, rng)
            seen = visible_fraction(pose, outline, cameras)
            if (0.25 <= seen < 1.0) if partial else seen == 1.0:
                poses.append(pose)
                break
        else:
            raise ScenarioError(
                f"target {target.name!r}: no {'partly' if partial else 'fully'} visible pose "
                f"found in {MAX_TRIES} tries; widen the camera view or shrink the motion ranges"
            )
    return Trajectory(motion.hold_s, np.stack(poses))
