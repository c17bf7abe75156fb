"""Where the cameras of a log sit relative to each other, when the log says.

Two sources, in order of preference:

1. the simulator's scenario record (``/camlog/scenario``): every camera's ``world_from_camera``
   (4, 4), matched by namespace or else by ``frame_id`` (a resynced copy keeps the frame);
2. a stereo right camera's projection ``P[0, 3] = -fx' * B``: the right camera's rectified
   frame sits ``B`` metres along the left one's x axis, and each camera's rectified frame is
   its optical frame turned by its ``R`` (``x_rect = R x``), so that
   ``left_from_right = [R_l^T R_r | R_l^T (B, 0, 0)]``. The left camera is the sibling
   namespace whose last part says ``left`` where this one says ``right``. Without a
   scenario the world is the left camera's optical frame.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from replay.messages import F64, CameraInfo
from replay.records import Scenario

__all__ = ["Rig", "baseline_m", "rig_poses", "stereo_partner"]


@dataclass(frozen=True)
class Rig:
    """``world_from_camera`` (4, 4) per camera namespace, and where each pose came from."""

    world_from_camera: dict[str, F64] = field(default_factory=dict)
    source: dict[str, str] = field(default_factory=dict)  # "scenario" or "baseline"
    world_is_scenario: bool = False  # else: the world is a left camera's optical frame


def baseline_m(info: CameraInfo) -> float | None:
    """Stereo baseline ``B = -P[0, 3] / P[0, 0]`` of a right camera; None when P has none.

    >>> import numpy as np
    >>> p = np.array([[500.0, 0, 320, -10.0], [0, 500, 240, 0], [0, 0, 1, 0]])
    >>> baseline_m(CameraInfo(0, "r", 640, 480, "plumb_bob", np.zeros(5), np.eye(3), p=p))
    0.02
    """
    fx, tx = float(info.p[0, 0]), float(info.p[0, 3])
    if fx <= 0 or tx == 0 or not np.isfinite(tx / fx):
        return None
    return -tx / fx


def stereo_partner(namespace: str, namespaces: Sequence[str]) -> str | None:
    """The left camera of a right camera namespace (``.../right`` -> ``.../left``).

    >>> stereo_partner("/stereo/right", ["/stereo/left", "/stereo/right"])
    '/stereo/left'
    """
    parent, _, last = namespace.rpartition("/")
    if "right" not in last:
        return None
    partner = f"{parent}/{last.replace('right', 'left')}"
    return partner if partner in namespaces else None


def _rectification(info: CameraInfo | None) -> F64:
    """A camera's rectifying rotation ``R`` (3, 3); the identity when it has none."""
    if info is None:
        return np.eye(3)
    r = np.asarray(info.r, dtype=np.float64)
    rotation = r.shape == (3, 3) and np.all(np.isfinite(r)) and \
        np.allclose(r @ r.T, np.eye(3), atol=1e-6) and np.linalg.det(r) > 0
    return r if rotation else np.eye(3)


def _matrix(value: Any) -> F64 | None:
    try:
        matrix = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return matrix if matrix.shape == (4, 4) and np.all(np.isfinite(matrix)) else None


def _scenario_poses(
    namespaces: Sequence[str], frame_ids: Mapping[str, str], scenario: Scenario
) -> dict[str, F64]:
    by_ns: dict[str, F64] = {}
    by_frame: dict[str, F64] = {}
    for camera in scenario.cameras:
        pose = _matrix(camera.world_from_camera)
        if pose is None:
            continue
        by_ns.setdefault(camera.namespace, pose)
        by_frame.setdefault(camera.frame_id, pose)
    poses = {}
    for ns in namespaces:
        pose = by_ns.get(ns)
        if pose is None and frame_ids.get(ns):
            pose = by_frame.get(frame_ids[ns])
        if pose is not None:
            poses[ns] = pose
    return poses


def rig_poses(
    namespaces: Sequence[str],
    *,
    frame_ids: Mapping[str, str],
    infos: Mapping[str, CameraInfo],
    scenario: Scenario | None,
) -> Rig:
    """Poses of the cameras the log can place (see the module docstring)."""
    poses = _scenario_poses(namespaces, frame_ids, scenario) if scenario else {}
    source = dict.fromkeys(poses, "scenario")
    world_is_scenario = bool(poses)
    for ns in namespaces:
        info = infos.get(ns)
        if ns in poses or info is None:
            continue
        partner = stereo_partner(ns, namespaces)
        b = baseline_m(info)
        if partner is None or b is None:
            continue
        if partner not in poses:
            if world_is_scenario:
                continue  # the left camera is not in a scenario world: nothing to anchor to
            poses[partner], source[partner] = np.eye(4), "baseline"
        rect_left, rect_right = _rectification(infos.get(partner)), _rectification(info)
        left_from_right = np.eye(4)
        left_from_right[:3, :3] = rect_left.T @ rect_right
        left_from_right[:3, 3] = rect_left.T @ np.array([b, 0.0, 0.0])
        poses[ns], source[ns] = poses[partner] @ left_from_right, "baseline"
    return Rig(poses, source, world_is_scenario)
