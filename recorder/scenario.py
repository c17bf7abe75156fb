"""Scenario specs: plain TOML data that, with its seed, fully determines a recording.

Built-in specs live in ``datasets/scenarios/NAME.toml``; any other spec file can be given by
path. Overrides (from the command line) are applied to the raw data before it is parsed, so
the resolved spec stored in the log is exactly what shaped the recording.
"""

from __future__ import annotations

import copy
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from replay.bounded import read_text, toml_loads

from .builtin import DEFAULT_SCENARIO, MAX_FRAMES, builtin_dir, builtin_names
from .cameras import CameraSpec, parse_camera
from .drift import DriftSpec, parse_drift
from .errors import ScenarioError
from .spec_table import SpecTable
from .target_spec import TargetSpec, parse_target
from .targets import check_target


@dataclass(frozen=True)
class ScenarioSpec:
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
    drifts: tuple[DriftSpec, ...] = ()  # cameras turned away from their calibration

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
) -> ScenarioSpec:
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
    text = read_text(path, ScenarioError, what="scenario file")
    try:
        raw = toml_loads(text, source, ScenarioError)
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"{source}: not valid TOML: {err}") from None
    raw = apply_overrides(raw, overrides or {})
    return parse_scenario(raw, source)


#: override key -> the camera field it sets on every camera
_CAMERA_OVERRIDES = (
    "width", "height", "hfov_rad", "intrinsics", "distortion_model", "distortion", "noise_std",
    "supersample", "encoding", "exposure_s",
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
        elif key == "drifts":  # added to the spec's own
            out["drifts"] = [*out.get("drifts", []), *value]
        else:
            out[key] = value
    return out


def parse_scenario(raw: dict[str, Any], source: str) -> ScenarioSpec:
    """Validate raw spec data and resolve cameras, rig poses and targets."""
    top = SpecTable(raw, "", source)
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
        cameras.append(parse_camera(table, f"cameras[{index}].", source, rate_hz, cameras))
    names = [c.name for c in cameras]
    if len(set(names)) != len(names):
        raise ScenarioError(f"{source}: cameras: names must be unique, got {names}")
    targets_raw = top.get("targets", [])
    if not isinstance(targets_raw, list):
        raise ScenarioError(f"{source}: targets: expected [[targets]] tables")
    targets = tuple(
        parse_target(t, f"targets[{i}].", source, cameras) for i, t in enumerate(targets_raw)
    )
    for index, target in enumerate(targets):
        try:
            check_target(target)
        except ScenarioError as err:
            raise ScenarioError(f"{source}: targets[{index}]: {err}") from None
    names = [t.name for t in targets]
    if len(set(names)) != len(names):
        raise ScenarioError(f"{source}: targets: names must be unique, got {names}")
    drifts_raw = top.get("drifts", [])
    if not isinstance(drifts_raw, list):
        raise ScenarioError(f"{source}: drifts: expected [[drifts]] tables")
    drifts = tuple(parse_drift(d, f"drifts[{i}].", source, cameras)
                   for i, d in enumerate(drifts_raw))
    top.check_unknown()
    scenario = ScenarioSpec(name, description, seed, duration_s, frames, start_stamp_ns,
                        tuple(cameras), targets, raw, source, drifts)
    if max(scenario.frame_counts) > MAX_FRAMES:
        raise ScenarioError(f"{source}: {max(scenario.frame_counts)} frames per camera is more "
                            f"than camlog records at once ({MAX_FRAMES}); shorten it")
    return scenario
