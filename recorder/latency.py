"""Lying stamps: a camera whose driver stamps its frames late (or early) by a fixed amount.

A scenario's ``[[latencies]]`` tables (or ``camlog record --latency CAMERA:MS[@S]``) each
stamp one camera's messages (image, camera_info, ground truth) ``latency_ms`` milliseconds
after the exposure they carry (negative: before it), from ``start_s`` after the recording's
start on (default 0; a later table of the same camera takes over then, as a driver
restarted with another queue would). A USB camera stamps on arrival, a GigE
camera at the end of its readout, a driver after its own queue: the stamps of two cameras
can then be 5-40 ms apart for frames exposed at one instant. Exposure times, jitter and
dropped frames are those of the camera's clock (:mod:`recorder.clock`), unchanged; the
ground truth is the pose at the exposure, stamped as the image is.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .cameras import CameraSpec, named_camera
from .spec_table import SpecTable

#: the largest latency a scenario accepts, in milliseconds
MAX_LATENCY_MS = 1000.0


@dataclass(frozen=True)
class LatencySpec:
    """One camera (by name) stamping its messages ``latency_ms`` after their exposure, for
    the frames exposed from ``start_s`` on."""

    camera: str
    latency_ms: float
    start_s: float = 0.0

    @property
    def latency_s(self) -> float:
        """The latency in seconds."""
        return self.latency_ms / 1000.0


def parse_latency(table: Any, where: str, source: str,
                  cameras: Sequence[CameraSpec]) -> LatencySpec:
    """Resolve one ``[[latencies]]`` table; ``camera`` is a camera's name or namespace."""
    f = SpecTable(table, where, source)
    latency = LatencySpec(camera=named_camera(f, cameras),
                          latency_ms=f.number("latency_ms", low=-MAX_LATENCY_MS,
                                              high=MAX_LATENCY_MS),
                          start_s=f.number("start_s", 0.0, low=0.0))
    f.check_unknown()
    return latency


def latency_at(camera: CameraSpec, latencies: Sequence[LatencySpec], t_s: float) -> float:
    """The latency (s) of a camera's frame exposed at ``t_s``: that of its latest table
    started by then (0 without one)."""
    started = [latency for latency in latencies
               if latency.camera == camera.name and latency.start_s <= t_s]
    return max(started, key=lambda latency: latency.start_s).latency_s if started else 0.0
