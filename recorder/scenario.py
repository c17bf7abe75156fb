"""Scenario specs: plain TOML data that, with its seed, fully determines a recording.

Built-in specs live in ``datasets/scenarios/NAME.toml``; any other spec file can be given by
path. Overrides (from the command line) are applied to the raw data before it is parsed, so
the resolved spec stored in the log is exactly what shaped the recording.
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from replay.camera import CAMERA_MODELS, FISHEYE_MODELS, CameraModel, focal_from_hfov
from replay.geometry import frame_from_axes, rotation_from_rpy
from replay.messages import F64, IMAGE_ENCODINGS

from .errors import ScenarioError

DEFAULT_SCENARIO = "mono_checkerboard"
RECORD_ENCODINGS = ("rgb8", "bgr8", "mono8")
#: 2 x 2 samples per pixel: without them MuJoCo's multisampling alone leaves ~0.07 px of
#: corner scatter; with them detected checkerboard corners sit within 0.2 px of the truth.
DEFAULT_SUPERSAMPLE = 2


def builtin_dir() -> Path:
    """Folder of the built-in scenario specs."""
    return Path(str(resources.files("camlog_datasets") / "scenarios"))


def builtin_names() -> list[str]:
    """Names of the scenario specs that ship with camlog."""
    return sorted(p.stem for p in builtin_dir().glob("*.toml"))


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


@dataclass(frozen=True)
class MotionSpec:
    """How a target moves: ``static`` or ``random_hold`` (random poses held ``hold_s``)."""

    kind: str
    hold_s: float
    center_m: F64
    xy_range_m: float
    z_range_m: tuple[float, float]
    max_tilt_rad: float
    partial_view_probability: float
    world_from_target: F64  # (4, 4), for static


@dataclass(frozen=True)
class TargetSpec:
    """A target: ``checkerboard`` (inner corners cols x rows) or a coloured ``box``."""

    name: str
    kind: str
    inner_corners: tuple[int, int]
    square_m: float
    border_squares: float
    size_m: F64  # box full extents (3,)
    rgba: tuple[float, float, float, float]
    motion: MotionSpec


@dataclass(frozen=True)
class Scenario:
    """A resolved scenario: cameras, targets, motion, timing and seed (all that shapes it)."""

    name: str
    description: str
    seed: int
    duration_s: float
    frames: int | None
    start_stamp_ns: int
    cameras: tuple[CameraSpec, ...]
    targets: tuple[TargetSpec, ...]
    spec: dict[str, Any]  # the resolved raw data
    source: str

    @property
    def rate_hz(self) -> float:
        """Frame rate of the first camera, in Hz."""
        return self.cameras[0].rate_hz

    @property
    def frame_count(self) -> int:
        """Frames of the first camera before drops (``frames``, or the duration at its rate)."""
        if self.frames is not None:
            return self.frames
        return max(1, round(self.duration_s * self.rate_hz))

    @property
    def frame_counts(self) -> tuple[int, ...]:
        """Frames per camera before drops: every camera records over the first one's span, so
        a camera at half the rate records half as many frames."""
        span_s = self.frame_count / self.rate_hz
        return tuple(self.frame_count if i == 0 else max(1, round(span_s * c.rate_hz))
                     for i, c in enumerate(self.cameras))


# --- loading -------------------------------------------------------------------------------

def load_scenario(
    name_or_path: str | None = None, overrides: dict[str, Any] | None = None
) -> Scenario:
    """Load a built-in scenario by name or a spec file by path, then apply ``overrides``."""
    name_or_path = name_or_path or DEFAULT_SCENARIO
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        source = str(path)
        if not path.is_file():
            raise ScenarioError(f"scenario file {path} does not exist")
    else:
        path = builtin_dir() / f"{name_or_path}.toml"
        source = f"built-in scenario {name_or_path!r}"
        if not path.is_file():
            raise ScenarioError(
                f"unknown scenario {name_or_path!r} (built-in: {', '.join(builtin_names())}; "
                "or give a path to a .toml spec)"
            )
    try:
        raw = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ScenarioError(f"{source}: not valid TOML: {err}") from None
    except OSError as err:
        raise ScenarioError(f"cannot read {path}: {err.strerror}") from None
    raw = apply_overrides(raw, overrides or {})
    return parse_scenario(raw, source)


#: override key -> the camera field it sets on every camera
_CAMERA_OVERRIDES = (
    "width", "height", "hfov_rad", "intrinsics", "distortion_model", "distortion", "noise_std",
    "supersample", "encoding",
)


def apply_overrides(raw: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Copy of ``raw`` with top-level and per-camera overrides (None values are ignored)."""
    out = copy.deepcopy(raw)
    for key, value in overrides.items():
        if value is None:
            continue
        if key in _CAMERA_OVERRIDES:
            for camera in out.get("cameras", []):
                if key == "intrinsics":
                    camera["fx"], camera["fy"], camera["cx"], camera["cy"] = value
                else:
                    camera[key] = value
        elif key == "frames":
            out["frames"] = value
            out.pop("duration_s", None)
        elif key == "duration_s":
            out["duration_s"] = value
            out.pop("frames", None)
        else:
            out[key] = value
    return out


class _Fields:
    """Typed access to one table of the spec, with errors that name the key."""

    def __init__(self, table: Any, where: str, source: str) -> None:
        if not isinstance(table, dict):
            raise ScenarioError(f"{source}: {where} must be a table")
        self.table, self.where, self.source = table, where, source
        self.used: set[str] = set()

    def _fail(self, key: str, what: str) -> ScenarioError:
        return ScenarioError(f"{self.source}: {self.where}{key}: {what}")

    def get(self, key: str, default: Any = ...) -> Any:
        self.used.add(key)
        if key not in self.table:
            if default is ...:
                raise self._fail(key, "missing")
            return default
        return self.table[key]

    def number(self, key: str, default: Any = ..., *, low: float | None = None,
               high: float | None = None, positive: bool = False) -> float:
        value = self.get(key, default)
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise self._fail(key, f"expected a number, got {value!r}")
        if positive and value <= 0:
            raise self._fail(key, f"must be > 0, got {value!r}")
        if (low is not None and value < low) or (high is not None and value > high):
            raise self._fail(key, f"must be within [{low}, {high}], got {value!r}")
        return float(value)

    def integer(self, key: str, default: Any = ..., *, low: int = 1) -> int:
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise self._fail(key, f"expected an integer >= {low}, got {value!r}")
        return value

    def text(self, key: str, default: Any = ..., *, choices: tuple[str, ...] | None = None) -> str:
        value = self.get(key, default)
        if not isinstance(value, str) or not value:
            raise self._fail(key, f"expected a non-empty string, got {value!r}")
        if choices is not None and value not in choices:
            raise self._fail(key, f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def vector(self, key: str, n: int | None, default: Any = ...) -> F64:
        value = self.get(key, default)
        ok = isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        )
        if not ok or (n is not None and len(value) != n):
            size = f"{n} numbers" if n is not None else "a list of numbers"
            raise self._fail(key, f"expected {size}, got {value!r}")
        return np.asarray(value, dtype=np.float64)

    def check_unknown(self) -> None:
        unknown = sorted(set(self.table) - self.used)
        if unknown:
            raise self._fail(unknown[0], "unknown key")


def parse_scenario(raw: dict[str, Any], source: str) -> Scenario:
    """Validate raw spec data and resolve cameras, rig poses and targets."""
    top = _Fields(raw, "", source)
    name = top.text("name")
    description = str(top.get("description", ""))
    seed = top.integer("seed", 0, low=0)
    rate_hz = top.number("rate_hz", 30.0, positive=True)
    frames = top.integer("frames", None) if "frames" in raw else None
    duration_s = top.number("duration_s", 10.0, positive=True)
    start_stamp_ns = top.integer("start_stamp_ns", 1_700_000_000_000_000_000, low=0)
    cameras_raw = top.get("cameras")
    if not isinstance(cameras_raw, list) or not cameras_raw:
        raise ScenarioError(f"{source}: cameras: expected at least one [[cameras]] table")
    cameras: list[CameraSpec] = []
    for index, table in enumerate(cameras_raw):
        cameras.append(_parse_camera(table, f"cameras[{index}].", source, rate_hz, cameras))
    names = [c.name for c in cameras]
    if len(set(names)) != len(names):
        raise ScenarioError(f"{source}: cameras: names must be unique, got {names}")
    targets_raw = top.get("targets", [])
    if not isinstance(targets_raw, list):
        raise ScenarioError(f"{source}: targets: expected [[targets]] tables")
    targets = tuple(
        _parse_target(t, f"targets[{i}].", source, cameras) for i, t in enumerate(targets_raw)
    )
    top.check_unknown()
    return Scenario(name, description, seed, duration_s, frames, start_stamp_ns,
                    tuple(cameras), targets, raw, source)


def _parse_camera(
    table: Any, where: str, source: str, rate_hz: float, earlier: list[CameraSpec]
) -> CameraSpec:
    f = _Fields(table, where, source)
    name = f.text("name")
    namespace = f.text("namespace", f"/{name}")
    if not namespace.startswith("/"):
        raise f._fail("namespace", f"must start with '/', got {namespace!r}")
    width, height = f.integer("width", 640), f.integer("height", 480)
    dist_model = f.text("distortion_model", "plumb_bob", choices=tuple(CAMERA_MODELS))
    fisheye = dist_model in FISHEYE_MODELS  # its field of view may pass 180 degrees
    hfov = f.number("hfov_rad", 0.6, low=1e-3, high=2 * math.pi - 0.1 if fisheye else 3.0)
    fx0 = (width / 2) / (hfov / 2) if fisheye else focal_from_hfov(width, hfov)
    fx = f.number("fx", fx0, positive=True)
    fy = f.number("fy", fx, positive=True)
    cx, cy = f.number("cx", (width - 1) / 2), f.number("cy", (height - 1) / 2)
    count = CAMERA_MODELS[dist_model]
    distortion = f.vector("distortion", None, [0.0] * count)
    if distortion.size > count:
        raise f._fail("distortion", f"{dist_model} takes at most {count} coefficients")
    k = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    model = CameraModel(width, height, k, dist_model, distortion)
    if "relative_to" in table:
        parent_name = f.text("relative_to")
        parents = [c for c in earlier if c.name == parent_name]
        if not parents:
            raise f._fail("relative_to", f"no earlier camera named {parent_name!r}")
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
            raise f._fail("forward", str(err)) from None
        baseline_tx = 0.0
    encoding = f.text("encoding", "rgb8", choices=RECORD_ENCODINGS)
    assert encoding in IMAGE_ENCODINGS
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
    )
    if spec.supersample > 4:
        raise f._fail("supersample", f"must be 1..4, got {spec.supersample}")
    f.check_unknown()
    return spec


def _parse_target(
    table: Any, where: str, source: str, cameras: list[CameraSpec]
) -> TargetSpec:
    f = _Fields(table, where, source)
    name = f.text("name")
    kind = f.text("kind", choices=("checkerboard", "box"))
    inner = (7, 6)
    square_m = 0.01
    border = 1.0
    size_m = np.array([0.02, 0.02, 0.01])
    rgba = (1.0, 0.0, 0.0, 1.0)
    if kind == "checkerboard":
        corners = f.vector("inner_corners", 2, [7, 6])
        if np.any(corners < 2) or np.any(corners != np.round(corners)):
            raise f._fail("inner_corners", f"expected two integers >= 2, got {corners.tolist()}")
        inner = (int(corners[0]), int(corners[1]))
        square_m = f.number("square_m", 0.01, positive=True)
        border = f.number("border_squares", 1.0, low=0.25)
    else:
        size_m = f.vector("size_m", 3, [0.02, 0.02, 0.01])
        if np.any(size_m <= 0):
            raise f._fail("size_m", "extents must be > 0")
        color = f.vector("rgba", 4, [1.0, 0.0, 0.0, 1.0])
        rgba = (float(color[0]), float(color[1]), float(color[2]), float(color[3]))
    motion = _parse_motion(f.get("motion", {"kind": "static"}), f"{where}motion.", source, cameras)
    f.check_unknown()
    return TargetSpec(name, kind, inner, square_m, border, size_m, rgba, motion)


def _parse_motion(table: Any, where: str, source: str, cameras: list[CameraSpec]) -> MotionSpec:
    f = _Fields(table, where, source)
    kind = f.text("kind", choices=("static", "random_hold"))
    world_from_target = np.eye(4)
    if kind == "static":
        target_pose = np.eye(4)
        target_pose[:3, :3] = rotation_from_rpy(f.vector("rotation_rpy_rad", 3, [0, 0, 0]))
        target_pose[:3, 3] = f.vector("position_m", 3, [0, 0, 0])
        frame = f.text("relative_to", "world")
        if frame == "world":
            world_from_target = target_pose
        else:
            parents = [c for c in cameras if c.name == frame]
            if not parents:
                raise f._fail("relative_to", f"no camera named {frame!r} (or use 'world')")
            world_from_target = parents[0].world_from_camera @ target_pose
    z_range = f.vector("z_range_m", 2, [0.15, 0.27])
    if z_range[0] > z_range[1]:
        raise f._fail("z_range_m", "lower bound above upper bound")
    spec = MotionSpec(
        kind=kind,
        hold_s=f.number("hold_s", 0.5, positive=True),
        center_m=f.vector("center_m", 3, [0.0, 0.0, 0.2]),
        xy_range_m=f.number("xy_range_m", 0.05, low=0.0),
        z_range_m=(float(z_range[0]), float(z_range[1])),
        max_tilt_rad=f.number("max_tilt_rad", 0.6, low=0.0, high=1.4),
        partial_view_probability=f.number("partial_view_probability", 0.0, low=0.0, high=1.0),
        world_from_target=world_from_target,
    )
    f.check_unknown()
    return spec
