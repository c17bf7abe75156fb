"""The simulator's scenario record (``/camlog/scenario``): what shaped a recording.

The recorder writes it once, first in the log: the resolved spec and seed, the camlog and
MuJoCo versions, every camera's true model and pose, its dropped frames, and the targets'
geometry. Calibration compares against it; the rerun export places cameras and projects
targets with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..camera import CameraModel
from ..lens_models import lens_model
from ..messages import F64
from .base import OMIT_NONE, JsonRecord

__all__ = ["RenderView", "Scenario", "ScenarioCamera", "ScenarioDrift", "ScenarioLatency",
           "ScenarioTarget"]


@dataclass(frozen=True)
class RenderView:
    """One pinhole view a wide camera was rendered from: its size (W, H), focal length and
    principal point in pixels, and its rotation ``camera_from_view`` (3, 3)."""

    size: tuple[int, int]
    focal_px: float
    principal_px: tuple[float, float]
    camera_from_view: F64


@dataclass(frozen=True)
class ScenarioCamera:
    """One simulated camera: its true model (``k`` (3, 3), ``d`` (N,)), its optical frame's
    pose ``world_from_camera`` (4, 4), how it was rendered and which frames it dropped."""

    name: str
    namespace: str
    frame_id: str
    width: int
    height: int
    k: F64
    distortion_model: str
    d: F64
    world_from_camera: F64
    render_size: tuple[int, int]
    supersample: int
    dropped_frames: list[int] = field(default_factory=list)
    #: a camera rendered as several pinhole views (a fisheye): the views, and the samples
    #: per output pixel side of its warp
    render_views: list[RenderView] | None = field(default=None, metadata=OMIT_NONE)
    samples_per_side: int | None = field(default=None, metadata=OMIT_NONE)
    #: shutter time of a camera with motion blur (frames stamped at mid-exposure)
    exposure_s: float | None = field(default=None, metadata=OMIT_NONE)

    def model(self) -> CameraModel:
        """The camera's true intrinsic model."""
        return CameraModel(self.width, self.height, self.k, self.distortion_model, self.d)

    def parameters(self) -> dict[str, float]:
        """True fx, fy, cx, cy and distortion coefficients by OpenCV name (k1, k2, p1, ...)."""
        names = lens_model(self.distortion_model).coefficients
        values = {"fx": float(self.k[0, 0]), "fy": float(self.k[1, 1]),
                  "cx": float(self.k[0, 2]), "cy": float(self.k[1, 2])}
        coefficients = [*np.asarray(self.d, dtype=np.float64).reshape(-1).tolist(), *[0.0] * 8]
        return values | dict(zip(names, coefficients, strict=False))


@dataclass(frozen=True)
class ScenarioTarget:
    """A target and its exact geometry in the target frame (``frame`` says where it sits):

    - ``checkerboard``: ``inner_corners`` (cols, rows), ``square_m``, the inner corners
      ``corners_in_target`` (N, 3), row-major;
    - ``charuco``: OpenCV's CharucoBoard of ``squares`` (cols, rows), ``square_m``,
      ``marker_m``, ``dictionary`` (``legacy_pattern`` False): its chessboard corners
      ``corners_in_target`` (N, 3) with ``corner_ids``, its ``marker_ids`` (M,) and
      ``marker_corners_in_target`` (M, 4, 3);
    - ``circles`` / ``acircles``: ``circles`` (cols, rows), ``spacing_m``, ``diameter_m``,
      ``asymmetric``, the circle centres ``centres_in_target`` (N, 3) in findCirclesGrid's
      order;
    - ``box``: ``size_m`` (3,), ``rgba``;
    - ``textured``: a box of ``size_m`` (3,) with a random texture of ``grain_m`` blobs.
    """

    name: str
    kind: str
    inner_corners: tuple[int, int] | None = field(default=None, metadata=OMIT_NONE)
    square_m: float | None = field(default=None, metadata=OMIT_NONE)
    corners_in_target: F64 | None = field(default=None, metadata=OMIT_NONE)
    size_m: F64 | None = field(default=None, metadata=OMIT_NONE)
    rgba: tuple[float, ...] | None = field(default=None, metadata=OMIT_NONE)
    squares: tuple[int, int] | None = field(default=None, metadata=OMIT_NONE)
    marker_m: float | None = field(default=None, metadata=OMIT_NONE)
    dictionary: str | None = field(default=None, metadata=OMIT_NONE)
    legacy_pattern: bool | None = field(default=None, metadata=OMIT_NONE)
    corner_ids: list[int] | None = field(default=None, metadata=OMIT_NONE)
    marker_ids: list[int] | None = field(default=None, metadata=OMIT_NONE)
    marker_corners_in_target: F64 | None = field(default=None, metadata=OMIT_NONE)
    circles: tuple[int, int] | None = field(default=None, metadata=OMIT_NONE)
    spacing_m: float | None = field(default=None, metadata=OMIT_NONE)
    diameter_m: float | None = field(default=None, metadata=OMIT_NONE)
    asymmetric: bool | None = field(default=None, metadata=OMIT_NONE)
    centres_in_target: F64 | None = field(default=None, metadata=OMIT_NONE)
    grain_m: float | None = field(default=None, metadata=OMIT_NONE)
    frame: str = ""

    def points_in_target(self) -> F64 | None:
        """Points ``(N, 3)`` worth projecting: a board's corners or circle centres, a box's
        vertices."""
        for given in (self.corners_in_target, self.centres_in_target):
            if given is None:
                continue
            points = np.asarray(given, dtype=np.float64)
            return points.reshape(-1, 3) if points.size and points.size % 3 == 0 else None
        box = self.kind in ("box", "textured")
        if box and self.size_m is not None and np.size(self.size_m) == 3:
            half = np.asarray(self.size_m, dtype=np.float64).reshape(3) / 2
            signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            return np.asarray(signs * half, dtype=np.float64)
        return None


@dataclass(frozen=True)
class ScenarioDrift:
    """A camera turned away from its calibration during the recording: by ``degrees``
    about ``axis`` of its optical frame (``roll`` about z, ``pitch`` about x, ``yaw`` about
    y, right-handed) from ``start_s`` after the recording's start (``start_stamp_ns``) on.
    Its camera_info keeps the calibration it started with; its ground-truth poses follow it.
    """

    camera: str
    namespace: str
    axis: str
    degrees: float
    start_s: float
    start_stamp_ns: int


@dataclass(frozen=True)
class ScenarioLatency:
    """A camera whose messages are stamped ``latency_ms`` milliseconds after the exposure
    they carry (negative: before it), for its frames exposed ``start_s`` or more after the
    recording's start: such a frame exposed at ``t`` carries the stamp ``t + latency_ms``.
    Exposure times, jitter and dropped frames are its clock's."""

    camera: str
    namespace: str
    latency_ms: float
    start_s: float = 0.0


@dataclass(frozen=True)
class Scenario(JsonRecord):
    """Everything that shaped a recording (``/camlog/scenario``, JSON)."""

    what = "scenario record"

    scenario: str
    source: str
    seed: int
    camlog_version: str
    mujoco_version: str
    renderer: str
    spec: dict[str, Any]
    cameras: list[ScenarioCamera]
    targets: list[ScenarioTarget]
    drifts: list[ScenarioDrift] | None = field(default=None, metadata=OMIT_NONE)
    latencies: list[ScenarioLatency] | None = field(default=None, metadata=OMIT_NONE)

    def latency_ns(self, camera: ScenarioCamera, at_s: float = 0.0) -> int:
        """How much later than its exposure a camera's frame exposed ``at_s`` after the
        recording's start is stamped (ns; 0 for a camera without a latency)."""
        started = [latency for latency in self.latencies or ()
                   if latency.camera == camera.name and latency.start_s <= at_s]
        return round(max(started, key=lambda latency: latency.start_s).latency_ms * 1e6) \
            if started else 0

    def camera_for(self, namespace: str, frame_id: str | None = None) -> ScenarioCamera | None:
        """The camera of a namespace, or else the one camera with ``frame_id`` (topics
        renamed by resync keep their frame ids)."""
        for camera in self.cameras:
            if camera.namespace == namespace:
                return camera
        matches = [c for c in self.cameras if frame_id and c.frame_id == frame_id]
        return matches[0] if len(matches) == 1 else None
