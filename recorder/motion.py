"""Target trajectories: a pose for every instant, planned up front from the seed."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial

import numpy as np
import numpy.typing as npt

from replay.geometry import invert, rotation_about
from replay.messages import F64

from .cameras import CameraSpec
from .coverage import ANCHORS, anchor_order, image_pose, view_angles
from .errors import ScenarioError
from .target_spec import TargetSpec
from .targets import center_in_target, outline_in_target

#: a fully visible board keeps this margin (px at 640 px width, scaled with the width) from
#: the image border: the calibration's detector drops corners within 8 px of it
IN_VIEW_MARGIN_PX = 8.0
REFERENCE_WIDTH_PX = 640
#: draws a pose slot gets; a slot none of them meets is drawn again (an image aim moves to
#: another anchor), up to MAX_ROUNDS times, before the scene counts as unable to show it
MAX_TRIES = 5000
MAX_ROUNDS = len(ANCHORS)
#: world-aimed draws judged at once (numpy over the batch; a stereo rig accepts about one
#: draw in 400), and how far (px, metres) the batch's arithmetic may stray from one draw's
#: own before a draw it rejects is looked at again
BATCH = 512
BATCH_SLACK = 1e-6


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


def _seen_fractions(
    world_from_target: F64, points_in_target: F64, cameras: tuple[CameraSpec, ...],
    margin_px: float,
) -> Iterator[float]:
    """Per camera, the fraction of the points that project inside the image, at least
    ``margin_px`` (scaled to a 640 px wide image) from its border (0 when one is behind it)."""
    for camera in cameras:
        margin = margin_px * min(1.0, camera.model.width / REFERENCE_WIDTH_PX)
        camera_from_target = invert(camera.world_from_camera) @ world_from_target
        pts = points_in_target @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
        if np.any(pts[:, 2] <= 0.01):
            yield 0.0
            continue
        uv = camera.model.project(pts)
        w, h = camera.model.width, camera.model.height
        inside = (
            (uv[:, 0] >= margin) & (uv[:, 0] <= w - 1 - margin)
            & (uv[:, 1] >= margin) & (uv[:, 1] <= h - 1 - margin)
        )
        yield float(np.mean(inside))


def visible_fraction(
    world_from_target: F64, points_in_target: F64, cameras: tuple[CameraSpec, ...],
    margin_px: float = IN_VIEW_MARGIN_PX,
) -> float:
    """Smallest fraction, over cameras, of the points that project inside the image, at
    least ``margin_px`` (scaled to a 640 px wide image) from its border."""
    return min(_seen_fractions(world_from_target, points_in_target, cameras, margin_px),
               default=1.0)


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


def catmull_rom(waypoints: F64, segment_s: float, t_s: float) -> F64:
    """The Catmull-Rom spline (continuous velocity) through ``waypoints`` ``(N, D)``, the
    ``i``-th reached at ``i * segment_s``, at time ``t_s`` ``(D,)`` (held at the ends)."""
    last = len(waypoints) - 1
    position = min(max(t_s, 0.0) / segment_s, float(last))
    k = min(int(position), last - 1)
    u = position - k
    p0, p1, p2, p3 = (waypoints[min(max(i, 0), last)] for i in range(k - 1, k + 3))
    return np.asarray(0.5 * (2 * p1 + (p2 - p0) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u * u
                             + (3 * p1 - p0 - 3 * p2 + p3) * u * u * u), dtype=np.float64)


@dataclass(frozen=True)
class SmoothTrajectory:
    """A board that never stops: a Catmull-Rom spline (continuous velocity) through random
    waypoints ``parameters[i]`` (x, y, z, yaw, tilt x, tilt y) reached at ``i * segment_s``."""

    target: TargetSpec
    segment_s: float
    parameters: F64  # (N, 6)

    def at(self, t_s: float) -> F64:
        """``world_from_target`` (4, 4) at time ``t_s``."""
        value = catmull_rom(self.parameters, self.segment_s, t_s)
        tilt_x, tilt_y = value[4], value[5]
        return _pose(self.target, np.array([*value[:4], math.atan2(tilt_y, tilt_x),
                                            math.hypot(tilt_x, tilt_y)]))


def _smooth_parameters(parameters: F64) -> F64:
    """Waypoints in coordinates a spline can blend: yaw unwrapped, the tilt as a vector."""
    yaw = np.unwrap(parameters[:, 3])
    tilt = np.column_stack([parameters[:, 5] * np.cos(parameters[:, 4]),
                            parameters[:, 5] * np.sin(parameters[:, 4])])
    return np.column_stack([parameters[:, :3], yaw, tilt])


def _seen_as_asked(world_from_target: F64, outline: F64, judged: tuple[CameraSpec, ...], *,
                   partly: bool) -> bool:
    """Every judged camera sees the whole outline, or, for a deliberately partial view, the
    worst of them sees 25-100 % of it."""
    lowest = 0.25 if partly else 1.0
    worst = 1.0
    for seen in _seen_fractions(world_from_target, outline, judged, IN_VIEW_MARGIN_PX):
        if seen < lowest:  # no need to look through the other cameras
            return False
        worst = min(worst, seen)
    return worst < 1.0 if partly else True


#: a draw of a pose slot: (what the plan keeps, ``world_from_target``), None when rejected
Draw = Callable[[], tuple[F64, F64] | None]


def _first_visible(draw: Draw, outline: F64, judged: tuple[CameraSpec, ...], *,
                   partly: bool) -> F64 | None:
    """What the plan keeps of the first of ``MAX_TRIES`` draws that ``judged`` sees as asked
    (:func:`_seen_as_asked`); None when none is."""
    for _try in range(MAX_TRIES):
        drawn = draw()
        if drawn is not None and _seen_as_asked(drawn[1], outline, judged, partly=partly):
            return drawn[0]
    return None


def _no_pose(target: TargetSpec, *, partly: bool, where: str, hint: str) -> ScenarioError:
    """The one-line error of a pose slot that no round of draws met."""
    return ScenarioError(
        f"target {target.name!r}: no {'partly' if partly else 'fully'} visible pose {where}; "
        f"{hint}")


def _batch_parameters(target: TargetSpec, u: F64) -> F64:
    """:func:`_random_parameters` of rows of six uniform draws ``u`` ``(B, 6)`` (each row's
    the very values one call draws, with the same arithmetic)."""
    motion = target.motion
    r, (z_low, z_high) = motion.xy_range_m, motion.z_range_m
    return np.column_stack([
        motion.center_m[0] + (-r + (r - -r) * u[:, 0]),
        motion.center_m[1] + (-r + (r - -r) * u[:, 1]),
        z_low + (z_high - z_low) * u[:, 2],
        -math.pi + (math.pi - -math.pi) * u[:, 3],
        0 + (2 * math.pi - 0) * u[:, 4],
        motion.max_tilt_rad * np.sqrt(u[:, 5]),
    ])


def _batch_rotations(axes: F64, angles: F64) -> F64:
    """Rotations ``(B, 3, 3)`` by ``angles`` ``(B,)`` about unit ``axes`` ``(B, 3)``."""
    k = np.zeros((len(axes), 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = axes[:, 2], -axes[:, 1], axes[:, 0]
    return (np.eye(3) + np.sin(angles)[:, None, None] * k
            + (1 - np.cos(angles))[:, None, None] * (k @ k))


def _maybe_seen(target: TargetSpec, parameters: F64, outline: F64,
                cameras: tuple[CameraSpec, ...], *, partly: bool) -> npt.NDArray[np.bool_]:
    """``(B,)`` which draws :func:`_seen_as_asked` may accept, judged for the whole batch at
    once: every draw it accepts is among them (the bounds are widened by
    :data:`BATCH_SLACK`), so the first of them it accepts is the first draw it accepts."""
    yaw = _batch_rotations(np.tile([0.0, 0.0, 1.0], (len(parameters), 1)), parameters[:, 3])
    tilt = _batch_rotations(np.column_stack([np.cos(parameters[:, 4]), np.sin(parameters[:, 4]),
                                             np.zeros(len(parameters))]), parameters[:, 5])
    rotation = tilt @ yaw @ np.diag([1.0, -1.0, -1.0])
    translation = parameters[:, :3] - rotation @ center_in_target(target)
    points_in_world = outline @ rotation.transpose(0, 2, 1) + translation[:, None, :]
    lowest = 0.25 if partly else 1.0
    maybe = np.ones(len(parameters), dtype=bool)
    short = np.zeros(len(parameters), dtype=bool)  # a camera may see less than all of it
    slack = BATCH_SLACK
    for camera in cameras:
        rows = np.flatnonzero(maybe)  # draws an earlier camera rejected stay rejected
        margin = IN_VIEW_MARGIN_PX * min(1.0, camera.model.width / REFERENCE_WIDTH_PX)
        camera_from_world = invert(camera.world_from_camera)
        pts = points_in_world[rows] @ camera_from_world[:3, :3].T + camera_from_world[:3, 3]
        in_front = (pts[..., 2] > 0.01 - slack).all(axis=1)
        uv = np.full((*pts.shape[:2], 2), -np.inf)
        if in_front.any():
            uv[in_front] = camera.model.project(pts[in_front].reshape(-1, 3)).reshape(
                -1, len(outline), 2)
        w, h = camera.model.width, camera.model.height
        loose = ((uv[..., 0] >= margin - slack) & (uv[..., 0] <= w - 1 - margin + slack)
                 & (uv[..., 1] >= margin - slack) & (uv[..., 1] <= h - 1 - margin + slack))
        strict = ((uv[..., 0] >= margin + slack) & (uv[..., 0] <= w - 1 - margin - slack)
                  & (uv[..., 1] >= margin + slack) & (uv[..., 1] <= h - 1 - margin - slack))
        maybe[rows] = in_front & (loose.mean(axis=1) >= lowest)
        short[rows] |= ~strict.all(axis=1) | (pts[..., 2] <= 0.01 + slack).any(axis=1)
    return maybe & short if partly else maybe


def _first_visible_in_world(target: TargetSpec, cameras: tuple[CameraSpec, ...],
                            outline: F64, rng: np.random.Generator, *,
                            partly: bool) -> F64 | None:
    """The parameters of the first of ``MAX_TRIES`` draws (:func:`_random_parameters`)
    that ``cameras`` see as asked, drawn and judged :data:`BATCH` at a time; ``rng`` is left
    where one draw after another would leave it."""
    for start in range(0, MAX_TRIES, BATCH):
        before = rng.bit_generator.state
        parameters = _batch_parameters(target, rng.random((min(BATCH, MAX_TRIES - start), 6)))
        for index in np.flatnonzero(_maybe_seen(target, parameters, outline, cameras,
                                                partly=partly)):
            if _seen_as_asked(_pose(target, parameters[index]), outline, cameras,
                              partly=partly):
                rng.bit_generator.state = before
                rng.random((int(index) + 1, 6))  # the draws up to this one, no further
                found: F64 = parameters[index]
                return found
    return None


def _world_parameters(target: TargetSpec, cameras: tuple[CameraSpec, ...], count: int,
                      rng: np.random.Generator) -> F64:
    """Pose parameters (:func:`_random_parameters`) ``(count, 6)``, each fully in view of
    every camera (or deliberately partly); a slot whose draws all miss is drawn again."""
    outline = outline_in_target(target)
    chosen = []
    for _ in range(count):
        partly = rng.uniform() < target.motion.partial_view_probability
        for _round in range(MAX_ROUNDS):
            found = _first_visible_in_world(target, cameras, outline, rng, partly=partly)
            if found is not None:
                chosen.append(found)
                break
        else:
            raise _no_pose(target, partly=partly,
                           where=f"found in {MAX_ROUNDS} x {MAX_TRIES} tries",
                           hint="widen the camera view or shrink the motion ranges")
    return np.stack(chosen)


def _image_draw(target: TargetSpec, camera: CameraSpec, anchor: int, outline: F64,
                rng: np.random.Generator, *, partly: bool) -> tuple[F64, F64] | None:
    pose = image_pose(target, camera, anchor, partial=partly, rng=rng)
    if pose is None or view_angles(camera, pose, outline).max() > target.motion.max_view_angle_rad:
        return None
    return pose, pose


def _anchors_from(anchor: int, rng: np.random.Generator) -> Iterator[int]:
    """``anchor``, then (drawn only when asked for) the other anchors in a random order."""
    yield anchor
    others = [a for a in range(len(ANCHORS)) if a != anchor]
    for index in rng.permutation(len(others)):
        yield others[int(index)]


def _image_poses(target: TargetSpec, cameras: tuple[CameraSpec, ...], count: int,
                 rng: np.random.Generator) -> F64:
    """Held poses that cover the image (:mod:`recorder.coverage`), each fully in view (or
    deliberately partly) of every camera, or of the camera it is aimed at (``visible_in``).
    A slot whose anchor no draw meets (a corner of one camera's image that the other camera
    cannot see) moves to another anchor, and that anchor is not tried again."""
    motion = target.motion
    outline = outline_in_target(target)
    unmet: set[tuple[int, int, bool]] = set()  # (camera, anchor, partly) no draw could meet
    poses = []
    for index, anchor in enumerate(anchor_order(count, rng)):
        aimed = index % len(cameras) if motion.visible_in == "any" else 0
        camera = cameras[aimed]
        judged = (camera,) if motion.visible_in == "any" else cameras
        partly = rng.uniform() < motion.partial_view_probability
        pose = None
        for tried in _anchors_from(anchor, rng):
            if (aimed, tried, partly) in unmet:
                continue
            draw = partial(_image_draw, target, camera, tried, outline, rng, partly=partly)
            pose = _first_visible(draw, outline, judged, partly=partly)
            if pose is not None:
                break
            unmet.add((aimed, tried, partly))
        if pose is None:
            raise _no_pose(target, partly=partly,
                           where=f"aimed at camera {camera.name!r}'s image found at any of the "
                                 f"{len(ANCHORS)} anchors in {MAX_TRIES} tries each",
                           hint="change distance_m or max_tilt_rad")
        poses.append(pose)
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
    step_s = motion.segment_s if motion.kind == "smooth" else motion.hold_s
    count = math.ceil(duration_s / step_s) + (2 if motion.kind == "smooth" else 1)
    if motion.aim == "image":
        return Trajectory(motion.hold_s, _image_poses(target, cameras, count, rng))
    chosen = _world_parameters(target, cameras, count, rng)
    if motion.kind == "smooth":
        return SmoothTrajectory(target, motion.segment_s, _smooth_parameters(chosen))
    return Trajectory(motion.hold_s, np.stack([_pose(target, p) for p in chosen]))
