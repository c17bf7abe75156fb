"""Motion blur: a frame as the mean of sub-frame renders over the camera's exposure.

A camera with ``exposure_s > 0`` keeps its shutter open from ``t - exposure_s / 2`` to
``t + exposure_s / 2`` around its frame stamp ``t`` (so the stamp and the truth pose are at
mid-exposure). The frame is the mean of ``n`` renders at the centres of ``n`` equal slices
of that interval, ``n`` chosen per frame so that no target point moves more than
``BLUR_STEP_PX`` in the image between two sub-frames (at most ``MAX_SUBFRAMES``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

import numpy as np

from replay.geometry import invert
from replay.messages import F64

from .cameras import CameraSpec
from .clock import Shot
from .render import SceneRenderer
from .rig_motion import CameraPoses
from .target_spec import TargetSpec
from .targets import outline_in_target

BLUR_STEP_PX = 1.0
MAX_SUBFRAMES = 12


class PoseSource(Protocol):
    """Anything that gives a target's pose at a time (a trajectory)."""

    def at(self, t_s: float) -> F64:
        """``world_from_target`` (4, 4) at ``t_s``."""
        ...


def subframe_times(t_s: float, exposure_s: float, count: int) -> F64:
    """Centres ``(count,)`` of ``count`` equal slices of the exposure around ``t_s``."""
    return np.asarray(t_s + exposure_s * ((np.arange(count) + 0.5) / count - 0.5))


def subframe_count(camera: CameraSpec, trajectories: Sequence[PoseSource],
                   outlines: Sequence[F64], t_s: float, *,
                   world_from_camera: Callable[[float], F64] | None = None) -> int:
    """Sub-frames that keep every target point within ``BLUR_STEP_PX`` between renders:
    from how far its outline moves in the image from the start to the end of exposure
    (``world_from_camera``: the camera's pose at a time, for a moving rig; default its
    pose at rest)."""
    if camera.exposure_s <= 0:
        return 1
    moved_px = 0.0
    half = camera.exposure_s / 2
    for trajectory, outline in zip(trajectories, outlines, strict=True):
        ends = []
        for t in (t_s - half, t_s + half):
            pose = invert(camera.world_from_camera if world_from_camera is None
                          else world_from_camera(t)) @ trajectory.at(t)
            ends.append(outline @ pose[:3, :3].T + pose[:3, 3])
        ahead = (ends[0][:, 2] > 0.01) & (ends[1][:, 2] > 0.01)
        if ahead.any():
            uv = [camera.model.project(end[ahead]) for end in ends]
            moved_px = max(moved_px, float(np.linalg.norm(uv[1] - uv[0], axis=1).max()))
    return max(1, min(MAX_SUBFRAMES, math.ceil(moved_px / BLUR_STEP_PX)))


def render_exposure(renderer: SceneRenderer, camera_index: int, camera: CameraSpec, *,
                    trajectories: Sequence[PoseSource], outlines: Sequence[F64],
                    t_s: float, poses: CameraPoses | None = None) -> np.ndarray:
    """The ideal render ``(Hr, Wr, 3)`` uint8 of one frame exposed around ``t_s`` (the
    renderer's poses are left at the last sub-frame); a moving rig's camera (``poses``)
    moves over the exposure too."""
    moving = poses is not None and poses.moving
    at = partial(poses.world_from_camera, camera_index) if poses is not None and moving \
        else None
    count = subframe_count(camera, trajectories, outlines, t_s, world_from_camera=at)
    total: np.ndarray | None = None
    for t in subframe_times(t_s, camera.exposure_s, count):
        if at is not None:
            renderer.place_camera(camera_index, at(float(t)))
        renderer.set_poses([trajectory.at(float(t)) for trajectory in trajectories])
        frame = renderer.render(camera_index)
        total = frame.astype(np.uint32) if total is None else total + frame
    assert total is not None
    return np.asarray((total + count // 2) // count, dtype=np.uint8)


def rendered_shots(
    renderer: SceneRenderer, cameras: Sequence[CameraSpec], targets: Sequence[TargetSpec],
    trajectories: Sequence[PoseSource], shots: Iterable[Shot], *,
    camera_poses: CameraPoses | None = None, every_frame: bool = False,
) -> Iterator[tuple[Shot, np.ndarray, list[F64]]]:
    """Each shot with its ideal render and the targets' ``world_from_target`` at its
    exposure (mid-exposure); cameras at one instant share one pose update. A camera is
    where ``camera_poses`` puts it at the shot's exposure (turned by its drifts, for its
    whole exposure; carried by a moving rig, over its exposure); default: at rest. A camera
    whose scene has not changed since its last frame gets that frame's render again (the
    same array, read-only) unless ``every_frame`` (what rendering costs without that)."""
    outlines = [outline_in_target(t) for t in targets]
    last_t: float | None = None
    poses: list[F64] = []
    drifts = camera_poses.drifts if camera_poses is not None else ()
    moving = camera_poses is not None and camera_poses.moving
    started = [0] * len(cameras)  # drifts each camera is turned by
    placed = [0] * len(cameras)  # times each camera was moved
    last = [_LastRender()] * len(cameras)
    for shot in shots:
        camera = cameras[shot.camera_index]
        now = sum(d.camera == camera.name and shot.t_s >= d.start_s for d in drifts)
        if camera_poses is not None and (moving or now != started[shot.camera_index]):
            renderer.place_camera(shot.camera_index,
                                  camera_poses.world_from_camera(shot.camera_index, shot.t_s))
            started[shot.camera_index] = now
            placed[shot.camera_index] += 1
        if camera.exposure_s > 0:
            rendered = render_exposure(renderer, shot.camera_index, camera,
                                       trajectories=trajectories, outlines=outlines,
                                       t_s=shot.t_s, poses=camera_poses)
            poses = [trajectory.at(shot.t_s) for trajectory in trajectories]
            last_t = None
        else:
            if shot.t_s != last_t:
                poses = [trajectory.at(shot.t_s) for trajectory in trajectories]
                renderer.set_poses(poses)
                last_t = shot.t_s
            scene = _scene_key(placed[shot.camera_index], poses)
            if every_frame or last[shot.camera_index].scene != scene:
                fresh = renderer.render(shot.camera_index)
                fresh.flags.writeable = False
                last[shot.camera_index] = _LastRender(scene, fresh)
            rendered = last[shot.camera_index].rendered
        yield shot, rendered, poses


def _scene_key(placed: int, world_from_targets: list[F64]) -> tuple[object, ...]:
    """What one camera's ideal render depends on while the scene is still: how many times
    the camera was moved, and every target's pose."""
    return (placed, *(pose.tobytes() for pose in world_from_targets))


@dataclass(frozen=True)
class _LastRender:
    """A camera's last ideal render and the scene it shows (the camera's placement count and
    every target's pose): a held pose is rendered once, not once per frame (the same scene
    renders to the same pixels; the noise is drawn per frame afterwards). Never written to."""

    scene: tuple[object, ...] = ()
    rendered: np.ndarray = field(default_factory=lambda: np.empty(0, np.uint8))
