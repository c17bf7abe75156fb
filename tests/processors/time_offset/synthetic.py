"""A waved board seen by a stereo pair whose second camera stamps late, projected exactly."""

from __future__ import annotations

import math

import numpy as np

from processors.calibration.rotation import matrices
from processors.time_offset import BoardTrack
from replay.camera import CameraModel
from replay.messages import F64

#: the first camera's frames and the rig: the second camera 2 cm along the first's x axis
PERIOD_S = 1 / 30
SECOND_FROM_FIRST = np.eye(4)
SECOND_FROM_FIRST[:3, 3] = [-0.02, 0.0, 0.0]
POINTS = np.array([[x * 0.01, y * 0.01, 0.0] for y in range(6) for x in range(7)])
START_NS = 1_700_000_000_000_000_000


def waypoints(seed: int) -> F64:
    """Random board poses (x, y, z, rotation vector) every 0.8 s, 0.28-0.38 m away."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.04, 0.04, (30, 2)), rng.uniform(0.28, 0.38, 30),
                            rng.uniform(-0.5, 0.5, (30, 3))])


def first_from_board(way: F64, t_s: float, *, held: bool = False) -> F64:
    """The board in the first camera at ``t_s``: a smooth path through the waypoints (a
    board held 0.5 s at each pose and jumping between them when ``held``)."""
    from recorder.motion import catmull_rom

    if held:
        t_s = math.floor(t_s / 0.5) * 0.5
    value = catmull_rom(way, 0.8, t_s)
    pose = np.eye(4)
    pose[:3, :3] = matrices(value[None, 3:])[0]
    pose[:3, 3] = value[:3] - pose[:3, :3] @ np.array([0.03, 0.025, 0.0])
    return pose


def tracks(seed: int, offset_ms: float, *, frames: int = 180, noise_px: float = 0.1,
           phase_s: float = 0.0, held: bool = False, start_s: tuple[float, float] = (0, 0),
           turned: bool = False) -> tuple[BoardTrack, BoardTrack]:
    """Both cameras' tracks: the second exposes ``phase_s`` after the first and stamps
    ``offset_ms`` late; ``turned``: its detections numbered from the board's other end."""
    rng = np.random.default_rng(seed + 1000)
    model = CameraModel.ideal(640, 480, 0.6)
    way = waypoints(seed)
    out = []
    for camera, (late_s, phase) in enumerate(((0.0, 0.0), (offset_ms / 1000, phase_s))):
        stamps, ids, corners = [], [], []
        for k in range(frames):
            t = start_s[camera] + k * PERIOD_S + phase
            pose = first_from_board(way, t, held=held)
            if camera:
                pose = SECOND_FROM_FIRST @ pose
            uv = model.project(POINTS @ pose[:3, :3].T + pose[:3, 3])
            uv += rng.normal(0.0, noise_px, uv.shape)
            stamps.append(START_NS + round((t + late_s) * 1e9))
            ids.append(np.arange(len(POINTS)))
            # a detector that starts from the board's other end calls point N-1-i point i
            corners.append(np.ascontiguousarray(uv[::-1]) if turned and camera else uv)
        out.append(BoardTrack(np.array(stamps, dtype=np.int64), ids, corners, model))
    return out[0], out[1]
