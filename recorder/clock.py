"""When each camera takes a frame: its rate, phase, jitter and dropped frames."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .cameras import CameraSpec
from .latency import LatencySpec, latency_at


@dataclass(frozen=True)
class Shot:
    """Camera ``camera_index`` takes its ``frame_index``-th frame at ``t_s`` (sim time,
    mid-exposure) and stamps it ``latency_s`` later (:mod:`recorder.latency`)."""

    t_s: float
    camera_index: int
    frame_index: int
    latency_s: float = 0.0

    @property
    def stamp_s(self) -> float:
        """The time the frame's messages are stamped with (sim time)."""
        return self.t_s + self.latency_s


def camera_times(
    camera: CameraSpec, frame_count: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Times ``(N,)`` in s of the kept frames and the indices ``(M,)`` of dropped ones.

    Jitter is Gaussian, clipped to 40 % of the frame period so that frames never swap order.
    """
    period = 1.0 / camera.rate_hz
    ideal = camera.phase_s + np.arange(frame_count) * period
    jitter = np.zeros(frame_count)
    if camera.jitter_s > 0:
        jitter = np.clip(rng.normal(0.0, camera.jitter_s, frame_count), -0.4 * period,
                         0.4 * period)
    dropped = np.zeros(frame_count, dtype=bool)
    if camera.drop_probability > 0:
        dropped = rng.uniform(size=frame_count) < camera.drop_probability
        dropped[0] = False
    times = np.maximum(ideal + jitter, 0.0)
    return times[~dropped], np.flatnonzero(dropped)


def schedule(
    cameras: tuple[CameraSpec, ...], frame_counts: Sequence[int],
    rngs: list[np.random.Generator], latencies: Sequence[LatencySpec] = (),
) -> tuple[list[Shot], dict[int, np.ndarray]]:
    """All shots in stamp order (cameras in spec order at equal stamps), and drops per
    camera; camera ``i`` takes ``frame_counts[i]`` frames before drops and stamps them
    after their exposure as ``latencies`` say (:mod:`recorder.latency`). Latencies do not
    touch the clock's random draws: a camera exposes at the same times with or without."""
    shots: list[Shot] = []
    drops: dict[int, np.ndarray] = {}
    for index, (camera, frame_count, rng) in enumerate(zip(cameras, frame_counts, rngs,
                                                           strict=True)):
        times, dropped = camera_times(camera, frame_count, rng)
        kept = np.setdiff1d(np.arange(frame_count), dropped)
        shots += [Shot(float(t), index, int(k), latency_at(camera, latencies, float(t)))
                  for t, k in zip(times, kept, strict=True)]
        drops[index] = dropped
    shots.sort(key=lambda s: (s.stamp_s, s.camera_index))
    return shots, drops
