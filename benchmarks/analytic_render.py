"""Scenarios rendered analytically: every pixel's ray through the true lens meets the board.

The MuJoCo recorder renders pinhole images and warps them through the lens (a fisheye as up
to 26 views a frame); here each output pixel's ray (``supersample`` x ``supersample`` rays a
pixel) is traced through the scenario's true model to the board plane and shaded exactly from
the target's black areas (:func:`recorder.targets.black_rectangles`: checkerboard squares,
ChArUco squares and marker bits) on its white plate, in front of a grey background. A camera
with an exposure is rendered as the mean of sub-frames over it (:mod:`recorder.exposure`:
stamps and truth at mid-exposure), and Gaussian noise of ``noise_std`` grey levels is added.
The log is what ``camlog record`` writes (images, camera_info, the true target poses and the
scenario record), so ``camlog calibrate`` measures itself against the truth on it.

Targets aimed at the image (``aim = "image"``) can be waved rather than held: the board
glides from one image-aimed pose to the next over ``hold_s`` (a smooth step: still at each
pose, fast between them), so a wide lens's video covers its image as a person waving a board
does.

Rendering costs the rays the board covers (those inside its outline's box) times the
sub-frames: about 0.1-0.3 s a frame at 640x480 and ``supersample`` 3 on one core.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from recorder.clock import schedule
from recorder.exposure import subframe_count, subframe_times
from recorder.motion import Trajectory, plan_trajectory
from recorder.scenario import ScenarioSpec, apply_overrides, parse_scenario
from recorder.target_spec import TargetSpec
from recorder.targets import black_rectangles, outline_in_target, target_record
from replay import Image, PoseStamped, open_writer
from replay._version import VERSION
from replay.camera import CameraModel
from replay.geometry import invert, quat_xyzw_from_rotation
from replay.messages import F64
from replay.records import Scenario as ScenarioRecord
from replay.records import ScenarioCamera
from replay.topics import SCENARIO, CameraTopics

#: grey levels of the background, the plate and the black areas
BACKGROUND, WHITE, BLACK = 110.0, 225.0, 25.0
#: rays per output pixel side
SUPERSAMPLE = 3
#: texels per square side of a target's texture
TEXELS = 64
#: seed streams as the recorder's (motion, clock, noise)
MOTION_STREAM, CLOCK_STREAM, NOISE_STREAM = 1, 2, 3
#: points along each side of the outline whose image bounds the rays traced
OUTLINE_STEPS = 16
#: margin (px) around the outline's image box
BOX_MARGIN_PX = 3


class BoardShading:
    """A planar target's exact shading in its own frame, as a texture of ``TEXELS`` texels a
    square side: every black area's edge of a checkerboard or ChArUco target
    (:func:`~recorder.targets.black_rectangles`: squares, marker bits) lies on a multiple
    of the square, so the squares' edges, whose crossings are the corners, fall exactly on
    texel edges."""

    def __init__(self, target: TargetSpec) -> None:
        outline = outline_in_target(target)
        border = target.border_m
        self.texel_m = target.square_m / TEXELS
        x0, y0 = outline[:, 0].min() - border, outline[:, 1].min() - border
        x1, y1 = outline[:, 0].max() + border, outline[:, 1].max() + border
        # the texture's origin on a square edge: squares' edges are texel edges
        self.origin = (math.floor(x0 / target.square_m) * target.square_m,
                       math.floor(y0 / target.square_m) * target.square_m)
        self.plate = (x0, x1, y0, y1)
        cols = math.ceil((x1 - self.origin[0]) / self.texel_m) + 1
        rows = math.ceil((y1 - self.origin[1]) / self.texel_m) + 1
        texture = np.full((rows + 1, cols + 1), BACKGROUND, dtype=np.float32)
        px = self.origin[0] + (np.arange(cols + 1) + 0.5) * self.texel_m
        py = self.origin[1] + (np.arange(rows + 1) + 0.5) * self.texel_m
        on_x, on_y = (px >= x0) & (px < x1), (py >= y0) & (py < y1)
        texture[np.ix_(on_y, on_x)] = WHITE
        for rx0, rx1, ry0, ry1 in black_rectangles(target):
            texture[np.ix_((py >= ry0) & (py < ry1), (px >= rx0) & (px < rx1))] = BLACK
        self.texture = texture

    @property
    def outline(self) -> F64:
        """The plate's corners ``(4, 3)`` in the board frame."""
        x0, x1, y0, y1 = self.plate
        return np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0]])

    def shade(self, x: F64, y: F64) -> F64:
        """Grey level ``(...)`` at board points ``(x, y)`` (metres, board frame)."""
        col = np.floor((x - self.origin[0]) / self.texel_m)
        row = np.floor((y - self.origin[1]) / self.texel_m)
        rows, cols = self.texture.shape
        inside = (col >= 0) & (col < cols) & (row >= 0) & (row < rows)
        col = np.where(inside, col, 0).astype(np.int32)
        row = np.where(inside, row, 0).astype(np.int32)
        return np.where(inside, self.texture[row, col], np.float32(BACKGROUND))


@dataclass
class CameraRays:
    """One camera's supersampled pixel rays ``(H s, W s, 3)`` (NaN where the model has
    none), the rays of its pixel centres and its model."""

    model: CameraModel
    rays: np.ndarray
    supersample: int
    centres: np.ndarray  # (H, W, 3) the rays of the pixel centres

    @classmethod
    def of(cls, model: CameraModel, supersample: int) -> CameraRays:
        """The rays of every sub-pixel sample (centres of an s x s split of each pixel):
        the model's unit rays at the pixel centres, interpolated between them (the lens is
        smooth over a pixel: the interpolation is off by under 1e-5 px)."""
        s = supersample
        u, v = np.meshgrid(np.arange(-1.0, model.width + 1.0),
                           np.arange(-1.0, model.height + 1.0))
        rays = model.pixel_rays(np.column_stack([u.ravel(), v.ravel()]))
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        grid = rays.reshape(model.height + 2, model.width + 2, 3).astype(np.float32)
        offsets = (np.arange(s) + 0.5) / s - 0.5
        h, w = model.height, model.width
        out = np.empty((h, s, w, s, 3), dtype=np.float32)
        for b, ov in enumerate(offsets):
            for a, ou in enumerate(offsets):
                # bilinear between the pixel centre and its neighbours towards the offset
                du, dv = int(np.sign(ou)), int(np.sign(ov))
                fu, fv = abs(ou), abs(ov)
                centre = grid[1:h + 1, 1:w + 1]
                side_u = grid[1:h + 1, 1 + du:w + 1 + du]
                side_v = grid[1 + dv:h + 1 + dv, 1:w + 1]
                corner = grid[1 + dv:h + 1 + dv, 1 + du:w + 1 + du]
                out[:, b, :, a] = ((1 - fu) * (1 - fv) * centre + fu * (1 - fv) * side_u
                                   + (1 - fu) * fv * side_v + fu * fv * corner)
        return cls(model, out.reshape(h * s, w * s, 3), s, grid[1:h + 1, 1:w + 1].copy())


def _box(model: CameraModel, camera_from_target: F64, outline: F64
         ) -> tuple[slice, slice] | None:
    """The pixel rows and columns that can see the target's plate (None: none)."""
    corners = np.vstack([outline, outline[:1]])
    steps = np.linspace(0.0, 1.0, OUTLINE_STEPS, endpoint=False)
    dense = np.vstack([a + (b - a) * steps[:, None] for a, b in itertools.pairwise(corners)])
    in_camera = dense @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
    if np.any(in_camera[:, 2] <= 1e-3) and not model.is_fisheye:
        return slice(0, model.height), slice(0, model.width)
    uv = model.project(in_camera)
    uv = uv[np.isfinite(uv).all(axis=1)]
    if not len(uv):
        return None
    lo = np.maximum(np.floor(uv.min(axis=0)) - BOX_MARGIN_PX, 0).astype(int)
    hi = np.minimum(np.ceil(uv.max(axis=0)) + BOX_MARGIN_PX,
                    [model.width - 1, model.height - 1]).astype(int)
    if np.any(hi < lo):
        return None
    return slice(int(lo[1]), int(hi[1]) + 1), slice(int(lo[0]), int(hi[0]) + 1)


def _shade_rays(shading: BoardShading, rays: np.ndarray, rotation: np.ndarray,
                origin: np.ndarray) -> np.ndarray:
    """Grey levels ``(...)`` of rays ``(..., 3)`` meeting the board: a ray's point at depth
    d is d r, in the board frame R^T (d r - t), whose z is zero at d = (R^T t)_z / (R^T r)_z
    (``rotation`` R, ``origin`` R^T t)."""
    along = rays @ rotation
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = origin[2] / along[..., 2]
        shade = shading.shade(depth * along[..., 0] - origin[0],
                              depth * along[..., 1] - origin[1])
    shade[~(depth > 0)] = BACKGROUND
    return shade


def render(camera: CameraRays, shading: BoardShading, camera_from_target: Sequence[F64]
           ) -> np.ndarray:
    """The image ``(H, W)`` float32 of the board at each of the sub-frame poses
    ``camera_from_target`` (4, 4) (their mean: motion blur). Each pixel is shaded by its
    centre's ray, and where it or a neighbour differs from the others (an edge), by the mean
    of its s x s rays."""
    model, s = camera.model, camera.supersample
    h, w = model.height, model.width
    fine = camera.rays.reshape(h, s, w, s, 3)
    centres = camera.centres
    total = np.full((h, w), BACKGROUND * len(camera_from_target), dtype=np.float32)
    for pose in camera_from_target:
        box = _box(model, pose, shading.outline)
        if box is None:
            continue
        rows, cols = box
        rotation = pose[:3, :3].astype(np.float32)
        origin = (pose[:3, :3].T @ pose[:3, 3]).astype(np.float32)
        shade = _shade_rays(shading, centres[rows, cols], rotation, origin)
        edge = np.zeros(shade.shape, dtype=bool)
        edge[:, 1:] |= shade[:, 1:] != shade[:, :-1]
        edge[:, :-1] |= shade[:, 1:] != shade[:, :-1]
        edge[1:, :] |= shade[1:, :] != shade[:-1, :]
        edge[:-1, :] |= shade[1:, :] != shade[:-1, :]
        ey, ex = np.nonzero(edge)
        if len(ey):
            sub = fine[ey + rows.start, :, ex + cols.start]  # (K, s, s, 3)
            shade[ey, ex] = _shade_rays(shading, sub, rotation, origin).mean(axis=(1, 2))
        total[rows, cols] += shade - BACKGROUND
    return np.asarray(total / len(camera_from_target), dtype=np.float32)


@dataclass(frozen=True)
class WavedTrajectory:
    """A board waved through held poses: from pose ``i`` to ``i + 1`` over ``hold_s`` with a
    smooth step (still at each pose), rotations interpolated along their geodesic."""

    hold_s: float
    world_from_target: F64  # (N, 4, 4)

    def at(self, t_s: float) -> F64:
        """``world_from_target`` (4, 4) at ``t_s``."""
        last = len(self.world_from_target) - 1
        x = min(max(t_s, 0.0) / self.hold_s, float(last))
        i = min(math.floor(x), last - 1) if last else 0
        if not last:
            return np.asarray(self.world_from_target[0])
        f = x - i
        w = f * f * (3.0 - 2.0 * f)
        a, b = self.world_from_target[i], self.world_from_target[i + 1]
        turn = b[:3, :3] @ a[:3, :3].T
        angle = math.acos(max(-1.0, min(1.0, (np.trace(turn) - 1.0) / 2.0)))
        out = np.eye(4)
        if angle < 1e-12:
            out[:3, :3] = a[:3, :3]
        else:
            axis = np.array([turn[2, 1] - turn[1, 2], turn[0, 2] - turn[2, 0],
                             turn[1, 0] - turn[0, 1]]) / (2.0 * math.sin(angle))
            out[:3, :3] = _axis_angle(axis, w * angle) @ a[:3, :3]
        out[:3, 3] = (1.0 - w) * a[:3, 3] + w * b[:3, 3]
        return out


def _axis_angle(axis: F64, angle: float) -> F64:
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.asarray(np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k)


def _rng(seed: int, stream: int, index: int) -> np.random.Generator:
    return np.random.default_rng([seed, stream, index])


def scenario_of(raw: dict[str, Any], overrides: dict[str, Any]) -> ScenarioSpec:
    """A scenario from spec data (as a TOML spec holds) and overrides (``seed``, ...)."""
    return parse_scenario(apply_overrides(raw, overrides), f"analytic {raw['name']!r}")


def _record(scenario: ScenarioSpec) -> ScenarioRecord:
    cameras = [ScenarioCamera(
        name=c.name, namespace=c.namespace, frame_id=c.frame_id, width=c.model.width,
        height=c.model.height, k=c.model.k, distortion_model=c.model.distortion_model,
        d=c.model.d, world_from_camera=c.world_from_camera,
        render_size=(c.model.width, c.model.height), supersample=SUPERSAMPLE,
        exposure_s=c.exposure_s or None) for c in scenario.cameras]
    return ScenarioRecord(
        scenario=scenario.name, source=scenario.source, seed=scenario.seed,
        camlog_version=VERSION, mujoco_version="", renderer="analytic", spec=scenario.spec,
        cameras=cameras, targets=[target_record(t) for t in scenario.targets])


def record_analytic(scenario: ScenarioSpec, output: Path, *, wave: bool = True) -> int:
    """Render ``scenario`` (one planar target) analytically into the log ``output``; the
    frames written. With ``wave``, held poses aimed at the image are waved through
    (:class:`WavedTrajectory`)."""
    (target,) = scenario.targets
    duration_s = max(n / c.rate_hz + c.phase_s
                     for n, c in zip(scenario.frame_counts, scenario.cameras, strict=True))
    planned = plan_trajectory(target, scenario.cameras, duration_s,
                              _rng(scenario.seed, MOTION_STREAM, 0))
    trajectory: Any = planned
    if wave and isinstance(planned, Trajectory) and target.motion.aim == "image":
        trajectory = WavedTrajectory(planned.hold_s, planned.world_from_target)
    shots, _dropped = schedule(scenario.cameras, scenario.frame_counts,
                               [_rng(scenario.seed, CLOCK_STREAM, i)
                                for i in range(len(scenario.cameras))])
    rays = [CameraRays.of(c.model, SUPERSAMPLE) for c in scenario.cameras]
    noise = [_rng(scenario.seed, NOISE_STREAM, i) for i in range(len(scenario.cameras))]
    shading, outline = BoardShading(target), outline_in_target(target)
    written = 0
    with open_writer(output, overwrite=True) as log:
        log.write(SCENARIO, _record(scenario).to_message(), log_time_ns=scenario.start_stamp_ns)
        for shot in shots:
            camera = scenario.cameras[shot.camera_index]
            camera_from_world = invert(camera.world_from_camera)
            count = subframe_count(camera, [trajectory], [outline], shot.t_s)
            poses = [camera_from_world @ trajectory.at(float(t))
                     for t in subframe_times(shot.t_s, camera.exposure_s, count)]
            image = render(rays[shot.camera_index], shading, poses)
            if camera.noise_std > 0:
                image += noise[shot.camera_index].standard_normal(
                    image.shape, dtype=np.float32) * camera.noise_std
            pixels = np.clip(np.rint(image), 0, 255).astype(np.uint8)
            stamp_ns = scenario.start_stamp_ns + round(shot.t_s * 1e9)
            topics = CameraTopics(camera.namespace)
            log.write(topics.image_raw, Image(stamp_ns, camera.frame_id, "mono8", pixels))
            log.write(topics.camera_info, camera.model.camera_info(
                stamp_ns=stamp_ns, frame_id=camera.frame_id, baseline_tx=camera.baseline_tx))
            truth = camera_from_world @ trajectory.at(shot.t_s)
            log.write(topics.ground_truth(target.name), PoseStamped(
                stamp_ns, camera.frame_id, truth[:3, 3], quat_xyzw_from_rotation(truth[:3, :3])))
            written += 1
    return written


__all__ = ["BoardShading", "CameraRays", "WavedTrajectory", "record_analytic", "render",
           "scenario_of"]
