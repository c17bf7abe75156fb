"""Target trajectories: a pose for every instant, planned up front from the seed."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from replay.geometry import invert, rotation_about
from replay.messages import F64

from .cameras import CameraSpec
from .coverage import anchor_order, image_pose, view_angles
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


def _random_parameters(target: TargetSpec, rng: np.random.Generator) -> F64:
    """A random pose as (x, y, z of the board's middle, yaw, tilt axis angle, tilt)."""
    motion = target.motion
    x = rng.uniform(-motion.xy_range_m, motion.xy_range_m)
    y = rng.uniform(-motion.xy_range_m, motion.xy_range_m)
    z = rng.uniform(*motion.z_range_m)
    yaw = rng.uniform(-math.pi, math.pi)
    axis_angle = rng.uniform(0, 2 * math.pi)
    tilt = motion.max_tilt_rad * math.sqrt(rng.uniform(0, 1))
    return np.array([motion.center_m[0] + x, motion.center_m[1] + y, z, yaw, axis_angle, tilt])


def _pose(target: TargetSpec, parameters: F64) -> F64:
    """``world_from_target`` of pose parameters: the board faces up (target z towards the
    ground), turned by ``yaw``, then tilted about a horizontal axis."""
    x, y, z, yaw_rad, axis_angle, tilt_rad = (float(v) for v in parameters)
    face_up = np.diag([1.0, -1.0, -1.0])
    yaw = rotation_about(np.array([0.0, 0.0, 1.0]), yaw_rad)
    tilt = rotation_about(np.array([math.cos(axis_angle), math.sin(axis_angle), 0.0]), tilt_rad)
    rotation = tilt @ yaw @ face_up
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = np.array([x, y, z]) - rotation @ center_in_target(target)
    return pose


@dataclass(frozen=True)
class SmoothTrajectory:
    """A board that never stops: a Catmull-Rom spline (continuous velocity) through random
    waypoints ``parameters[i]`` (x, y, z, yaw, tilt x, tilt y) reached at ``i * segment_s``."""

    target: TargetSpec
    segment_s: float
    parameters: F64  # (N, 6)

    def at(self, t_s: float) -> F64:
        """``world_from_target`` (4, 4) at time ``t_s``."""
        last = len(self.parameters) - 1
        position = min(max(t_s, 0.0) / self.segment_s, float(last))
        k = min(int(position), last - 1)
        u = position - k
        p0, p1, p2, p3 = (self.parameters[min(max(i, 0), last)] for i in range(k - 1, k + 3))
        value = 0.5 * (2 * p1 + (p2 - p0) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u * u
                       + (3 * p1 - p0 - 3 * p2 + p3) * u * u * u)
        tilt_x, tilt_y = value[4], value[5]
        return _pose(self.target, np.array([*value[:4], math.atan2(tilt_y, tilt_x),
                                            math.hypot(tilt_x, tilt_y)]))


def _smooth_parameters(parameters: F64) -> F64:
    """Waypoints in coordinates a spline can blend: yaw unwrapped, the tilt as a vector."""
    yaw = np.unwrap(parameters[:, 3])
    tilt = np.column_stack([parameters[:, 5] * np.cos(parameters[:, 4]),
                            parameters[:, 5] * np.sin(parameters[:, 4])])
    return np.column_stack([parameters[:, :3], yaw, tilt])


def _image_poses(target: TargetSpec, cameras: tuple[CameraSpec, ...], count: int,
                 rng: np.random.Generator) -> F64:
    """Held poses that cover the image (:mod:`recorder.coverage`), each fully in view (or
    deliberately partly) of every camera, or of the camera it is aimed at (``visible_in``)."""
    motion = target.motion
    outline = outline_in_target(target)
    poses = []
    for index, anchor in enumerate(anchor_order(count, rng)):
        camera = cameras[index % len(cameras)] if motion.visible_in == "any" else cameras[0]
        judged = (camera,) if motion.visible_in == "any" else cameras
        partial = rng.uniform() < motion.partial_view_probability
        for _try in range(MAX_TRIES):
            pose = image_pose(target, camera, anchor, partial=partial, rng=rng)
            if pose is None or view_angles(camera, pose, outline).max() > motion.max_view_angle_rad:
                continue
            seen = visible_fraction(pose, outline, judged)
            if (0.25 <= seen < 1.0) if partial else seen == 1.0:
                poses.append(pose)
                break
        else:
            raise ScenarioError(
                f"target {target.name!r}: no {'partly' if partial else 'fully'} visible pose "
                f"aimed at the image found in {MAX_TRIES} tries; change distance_m or "
                "max_tilt_rad")
    return np.stack(poses)


def plan_trajectory(
    target: TargetSpec, cameras: tuple[CameraSpec, ...], duration_s: float,
    rng: np.random.Generator,
) -> Trajectory | SmoothTrajectory:
    """Poses for ``duration_s``; random poses (held ones, or a smooth path's waypoints) are
    fully in view of every camera, except a ``partial_view_probability`` share that are
    deliberately cut by the image border."""
    motion = target.motion
    if motion.kind == "static":
        return Trajectory(duration_s + 1.0, motion.world_from_target[None])
    outline = outline_in_target(target)
    step_s = motion.segment_s if motion.kind == "smooth" else motion.hold_s
    count = math.ceil(duration_s / step_s) + (2 if motion.kind == "smooth" else 1)
    if motion.aim == "image":
        return Trajectory(motion.hold_s, _image_poses(target, cameras, count, rng))
    chosen = []
    for _ in range(count):
        partial = rng.uniform() < motion.partial_view_probability
        for _try in range(MAX_TRIES):
            parameters = _random_parameters(target, rng)
            seen = visible_fraction(_pose(target, parameters), outline, cameras)
            if (0.25 <= seen < 1.0) if partial else seen == 1.0:
                chosen.append(parameters)
                break
        else:
            raise ScenarioError(
                f"target {target.name!r}: no {'partly' if partial else 'fully'} visible pose "
                f"found in {MAX_TRIES} tries; widen the camera view or shrink the motion ranges"
            )
    if motion.kind == "smooth":
        return SmoothTrajectory(target, motion.segment_s, _smooth_parameters(np.stack(chosen)))
    return Trajectory(motion.hold_s, np.stack([_pose(target, p) for p in chosen]))
