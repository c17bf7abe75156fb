"""Simulated cameras of a scenario spec: model, pose, encoding, timing."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from replay.camera import CameraModel, focal_from_hfov
from replay.geometry import frame_from_axes, rotation_from_rpy
from replay.lens_models import LENS_MODELS
from replay.messages import F64

from .spec_table import SpecTable

RECORD_ENCODINGS = ("rgb8", "bgr8", "mono8")
#: 2 x 2 samples per pixel: without them MuJoCo's multisampling alone leaves ~0.07 px of
#: corner scatter; with them detected checkerboard corners sit within 0.2 px of the truth.
DEFAULT_SUPERSAMPLE = 2


@dataclass(frozen=True)
class CameraSpec:
    """One simulated camera. ``world_from_camera`` (4, 4) is its optical frame in the world."""

    name: str
    namespace: str
    frame_id: str
    model: CameraModel
    world_from_camera: F64
    encoding: str
    noise_std: float
    supersample: int
    rate_hz: float
    phase_s: float
    jitter_s: float
    drop_probability: float
    baseline_tx: float  # CameraInfo P[0, 3] (= -fx * B for the right camera of a rig)
    #: shutter open time; > 0 averages sub-frame renders over it (motion blur), the frame
    #: stamped at mid-exposure
    exposure_s: float = 0.0


def parse_camera(
    table: Any, where: str, source: str, rate_hz: float, earlier: list[CameraSpec]
) -> CameraSpec:
    """Resolve one ``[[cameras]]`` table (``earlier`` cameras for ``relative_to``)."""
    f = SpecTable(table, where, source)
    name = f.text("name")
    namespace = f.text("namespace", f"/{name}")
    if not namespace.startswith("/"):
        raise f.fail("namespace", f"must start with '/', got {namespace!r}")
    width = f.integer("width", 640)
    height = f.integer("height", 480)
    dist_model = f.text("distortion_model", "plumb_bob", choices=tuple(LENS_MODELS))
    fisheye = LENS_MODELS[dist_model].fisheye
    # a pinhole's field of view stays below 180 degrees; a fisheye's may pass it
    hfov = f.number("hfov_rad", 0.6, low=1e-3, high=2 * math.pi - 0.1 if fisheye else 3.0)
    fx0 = (width / 2) / (hfov / 2) if fisheye else focal_from_hfov(width, hfov)
    fx = f.number("fx", fx0, positive=True)
    fy = f.number("fy", fx, positive=True)
    cx = f.number("cx", (width - 1) / 2)
    cy = f.number("cy", (height - 1) / 2)
    count = len(LENS_MODELS[dist_model].coefficients)
    distortion = f.vector("distortion", None, [0.0] * count)
    if distortion.size > count:
        raise f.fail("distortion", f"{dist_model} takes at most {count} coefficients, "
                      f"got {distortion.size}")
    k = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    model = CameraModel(width, height, k, dist_model, distortion)
    if "relative_to" in table:
        parent_name = f.text("relative_to")
        parents = [c for c in earlier if c.name == parent_name]
        if not parents:
            raise f.fail("relative_to", f"no earlier camera named {parent_name!r}")
        parent = parents[0]
        parent_from_camera = np.eye(4)
        parent_from_camera[:3, :3] = rotation_from_rpy(f.vector("rotation_rpy_rad", 3, [0, 0, 0]))
        parent_from_camera[:3, 3] = f.vector("translation_m", 3)
        world_from_camera = parent.world_from_camera @ parent_from_camera
        baseline_tx = -fx * float(parent_from_camera[0, 3])
    else:
        try:
            world_from_camera = frame_from_axes(
                f.vector("position_m", 3), forward=f.vector("forward", 3),
                right=f.vector("right", 3),
            )
        except ValueError as err:
            raise f.fail("forward", str(err)) from None
        baseline_tx = 0.0
    encoding = f.text("encoding", "rgb8", choices=RECORD_ENCODINGS)
    spec = CameraSpec(
        name=name, namespace=namespace.rstrip("/"),
        frame_id=f.text("frame_id", f"{name}_optical_frame"),
        model=model, world_from_camera=world_from_camera, encoding=encoding,
        noise_std=f.number("noise_std", 0.0, low=0.0),
        supersample=f.integer("supersample", DEFAULT_SUPERSAMPLE),
        rate_hz=f.number("rate_hz", rate_hz, positive=True),
        phase_s=f.number("phase_s", 0.0, low=0.0),
        jitter_s=f.number("jitter_s", 0.0, low=0.0),
        drop_probability=f.number("drop_probability", 0.0, low=0.0, high=0.9),
        baseline_tx=baseline_tx,
        exposure_s=f.number("exposure_s", 0.0, low=0.0),
    )
    if spec.supersample > 4:
        raise f.fail("supersample", f"must be 1..4, got {spec.supersample}")
    if spec.exposure_s >= 1.0 / spec.rate_hz:
        raise f.fail("exposure_s", f"must be shorter than the frame period "
                                   f"({1.0 / spec.rate_hz:.4g} s), got {spec.exposure_s}")
    f.check_unknown()
    return spec
