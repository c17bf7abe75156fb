"""Poses that cover the image: a board facing a camera, pushed in turn into each image
corner, each edge and the middle (``aim = "image"``).

camera_calibration rates coverage by where boards sit in the image (its X, Y, size and skew
parameters); random poses around a point in the world leave the image corners empty. Here
each pose picks an anchor (the 9 regions are visited in a random order, every 9 poses), an
orientation facing the camera along the ray to the board (rows within 23 degrees of the
image's rows or columns, tilted up to ``max_tilt_rad``; a fisheye sees boards far off its
axis face on, not edge on) and a distance,
then slides the board across the image until its outline touches the anchor's borders (a
margin plus a little random room) or, for a deliberately partial view, hangs 25-60 % of its
size over them.
"""

from __future__ import annotations

import math

import numpy as np

from replay.geometry import rotation_about
from replay.messages import F64

from .cameras import CameraSpec
from .target_spec import TargetSpec
from .targets import center_in_target, outline_in_target

#: (u, v) anchors: 0 pushes to the low border, 1 to the high one, None leaves it free
ANCHORS: tuple[tuple[float | None, float | None], ...] = (
    (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0),
    (None, 0.0), (None, 1.0), (0.0, None), (1.0, None), (None, None),
)
#: distance (px at 640 px width) a fully visible outline keeps from the border
MARGIN_PX = 10.0
SLIDES = 4


def anchor_order(count: int, rng: np.random.Generator) -> list[int]:
    """Anchor index per pose: every run of 9 poses visits each anchor once, shuffled."""
    order: list[int] = []
    while len(order) < count:
        order += rng.permutation(len(ANCHORS)).tolist()
    return order[:count]


def view_angles(camera: CameraSpec, world_from_target: F64, points_in_target: F64) -> F64:
    """Angles (rad) of target points from a camera's optical axis ``(N,)``."""
    camera_from_target = np.linalg.inv(camera.world_from_camera) @ world_from_target
    points = points_in_target @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
    return np.asarray(np.arccos(np.clip(points[:, 2] / np.linalg.norm(points, axis=1), -1, 1)))


def _towards(ray: F64) -> F64:
    """The smallest rotation taking the optical axis (0, 0, 1) to the unit ``ray``."""
    axis = np.array([-ray[1], ray[0], 0.0])  # (0, 0, 1) x ray
    sine = float(np.linalg.norm(axis))
    if sine < 1e-12:
        return np.eye(3) if ray[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return rotation_about(axis, math.atan2(sine, float(ray[2])))


def image_pose(target: TargetSpec, camera: CameraSpec, anchor: int, *, partial: bool,
               rng: np.random.Generator) -> F64 | None:
    """``world_from_target`` of a board facing ``camera``, its outline pushed to the anchor's
    borders (over them when ``partial``); None when it would pass behind the camera."""
    motion = target.motion
    model = camera.model
    size = np.array([model.width - 1.0, model.height - 1.0])
    margin = MARGIN_PX * min(1.0, model.width / 640)
    # rows roughly along or across the image (a diamond's corners stay far from the border)
    roll = rotation_about(np.array([0.0, 0.0, 1.0]),
                          int(rng.integers(4)) * math.pi / 2 + rng.uniform(-0.4, 0.4))
    axis_angle = rng.uniform(0, 2 * math.pi)
    tilt = rotation_about(np.array([math.cos(axis_angle), math.sin(axis_angle), 0.0]),
                          motion.max_tilt_rad * math.sqrt(rng.uniform(0, 1)))
    facing = tilt @ roll  # in the frame of the ray to the board: its z along the ray
    distance = rng.uniform(*motion.distance_m)
    free = rng.uniform(0, 1, 2)  # where a free axis puts the board between the borders
    overhang = rng.uniform(0.25, 0.6, 2) if partial else -rng.uniform(0, 0.03, 2)
    sides = ANCHORS[anchor]
    if partial and sides == (None, None):  # a partial view needs a border to hang over
        sides = (float(rng.integers(2)), None)
    outline = outline_in_target(target)
    middle = center_in_target(target)
    pixel = np.array([model.cx, model.cy])
    camera_from_target = np.eye(4)
    for slide in range(SLIDES + 1):
        ray = model.pixel_rays(pixel[None])[0]
        rotation = _towards(ray) @ facing  # the board faces the camera along its ray
        camera_from_target[:3, :3] = rotation
        camera_from_target[:3, 3] = ray * distance - rotation @ middle
        points = outline @ rotation.T + camera_from_target[:3, 3]
        if np.any(points[:, 2] <= 0.01):
            return None
        if slide == SLIDES:
            break
        uv = model.project(points)
        low, high = uv.min(axis=0), uv.max(axis=0)
        extent = high - low
        for axis, side in enumerate(sides):
            if side is None:
                goal = margin + free[axis] * max(0.0, size[axis] - 2 * margin - extent[axis])
                pixel[axis] += goal - low[axis]
            elif side == 0.0:
                pixel[axis] += margin - overhang[axis] * extent[axis] - low[axis]
            else:
                pixel[axis] += size[axis] - margin + overhang[axis] * extent[axis] - high[axis]
        pixel = np.clip(pixel, 0.0, size)
    return np.asarray(camera.world_from_camera @ camera_from_target)
