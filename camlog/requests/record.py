"""``camlog record``'s request: the scenario, where its log goes, and the overrides of the
scenario's cameras, length and seed."""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from recorder.builtin import DEFAULT_SCENARIO, MAX_FRAMES, builtin_names
from replay.format_names import WRITE_FORMATS
from replay.lens_models import LENS_MODELS

from . import fields as common
from .fields import option
from .values import bounded_int, non_negative, number, output_path, positive

__all__ = ["RecordRequest"]

#: longest recording in seconds and largest image side the command line accepts
MAX_DURATION_S = 86_400.0
MAX_SIDE = 8192
#: MODEL:K1,K2,... for every lens model, as --distortion takes them
DISTORTION_FORMS = [f"{m.name}:{','.join(m.coefficients)}" for m in LENS_MODELS.values()]
#: the axes a camera may drift about (recorder.drift.AXES, without loading the recorder)
DRIFT_AXES = ("roll", "pitch", "yaw")


def _floats(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.replace(" ", "").split(",") if v)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}"
        ) from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values


def _intrinsics(text: str) -> tuple[float, ...]:
    values = _floats(text)
    if len(values) != 4:
        raise argparse.ArgumentTypeError(f"expected FX,FY,CX,CY, got {text!r}")
    return values


def _resolution(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w < 16 or h < 16:
        raise argparse.ArgumentTypeError(f"resolution {text} is too small (min 16x16)")
    if w > MAX_SIDE or h > MAX_SIDE:
        raise argparse.ArgumentTypeError(
            f"resolution {text} is too large (at most {MAX_SIDE} pixels per side)")
    return w, h


def _distortion(text: str) -> tuple[str, tuple[float, ...]]:
    model, _, coeffs = text.partition(":")
    if model not in LENS_MODELS or not coeffs:
        raise argparse.ArgumentTypeError(
            f"expected {', '.join(DISTORTION_FORMS[:-1])} or {DISTORTION_FORMS[-1]}, "
            f"got {text!r}")
    values = _floats(coeffs)
    count = len(LENS_MODELS[model].coefficients)
    if len(values) != count:
        raise argparse.ArgumentTypeError(f"{model} has {count} coefficients, got {len(values)}")
    return model, values


def _drift(text: str) -> dict[str, Any]:
    """``CAMERA:AXIS:DEGREES@SECONDS`` as a scenario's ``[[drifts]]`` table."""
    where, _, start = text.rpartition("@")
    camera, _, rest = where.partition(":")
    axis, _, degrees = rest.partition(":")
    try:
        numbers = (float(degrees), float(start))
    except ValueError:
        numbers = (math.nan, math.nan)
    if not camera or axis not in DRIFT_AXES or not all(math.isfinite(v) for v in numbers):
        raise argparse.ArgumentTypeError(
            f"expected CAMERA:AXIS:DEGREES@SECONDS with AXIS one of {', '.join(DRIFT_AXES)}, "
            f"e.g. right:pitch:0.1@2.5, got {text!r}")
    return {"camera": camera, "axis": axis, "degrees": numbers[0], "start_s": numbers[1]}


def _latency(text: str) -> dict[str, Any]:
    """``CAMERA:MS[@SECONDS]`` as a scenario's ``[[latencies]]`` table."""
    where, at, start = text.rpartition("@") if "@" in text else (text, "", "0")
    camera, _, ms = where.rpartition(":")
    try:
        numbers = (float(ms), float(start))
    except ValueError:
        numbers = (math.nan, math.nan)
    if not camera or not all(math.isfinite(v) for v in numbers):
        raise argparse.ArgumentTypeError(
            f"expected CAMERA:MS or CAMERA:MS@SECONDS, e.g. right:17, left:-5 or "
            f"right:25@6, got {text!r}")
    table = {"camera": camera, "latency_ms": numbers[0]}
    return table | ({"start_s": numbers[1]} if at else {})


@dataclass(frozen=True, kw_only=True)
class RecordRequest:
    """Simulate a scenario in MuJoCo and write its camera log."""

    scenario: str = option(
        DEFAULT_SCENARIO, nargs="?",
        help=f"built-in scenario name ({', '.join(builtin_names())}) or path to a .toml spec "
             f"(default: {DEFAULT_SCENARIO})")
    output: Path | None = option(
        None, "-o", "--output", type=output_path,
        help="output log: NAME.mcap (default), NAME.bag (ROS1) or a directory name "
             "(rosbag2); default: recordings/SCENARIO.mcap")
    format: str | None = option(None, "--format", choices=tuple(sorted(WRITE_FORMATS)),
                                help="output format (default: from the output name; .mcap "
                                     "when none)")
    overwrite: bool = common.overwrite()
    seed: int | None = option(None, "--seed", type=bounded_int(0, 2**63 - 1),
                              help="random seed (board poses, stamps, noise)")
    duration: float | None = option(
        None, "--duration", type=number(above=0.0, high=MAX_DURATION_S), metavar="S",
        exclusive="length", help=f"recording length in seconds (at most {MAX_DURATION_S:g})")
    frames: int | None = option(None, "--frames", type=bounded_int(1, MAX_FRAMES), metavar="N",
                                exclusive="length",
                                help=f"frames per camera (at most {MAX_FRAMES})")
    resolution: tuple[int, int] | None = option(
        None, "--resolution", type=_resolution, metavar="WxH",
        help="image size of every camera, e.g. 640x480")
    hfov: float | None = option(None, "--hfov", type=positive, metavar="RAD",
                                help="horizontal field of view (rad)")
    intrinsics: tuple[float, ...] | None = option(
        None, "--intrinsics", type=_intrinsics, metavar="FX,FY,CX,CY",
        help="pinhole intrinsics in pixels (overrides --hfov)")
    distortion: tuple[str, tuple[float, ...]] | None = option(
        None, "--distortion", type=_distortion, metavar="MODEL:K1,K2,...",
        help=f"lens distortion, e.g. plumb_bob:-0.2,0.05,0,0,0; {', '.join(DISTORTION_FORMS)} "
             "(a fisheye model is rendered as several views)")
    noise: float | None = option(None, "--noise", type=non_negative, metavar="SIGMA",
                                 help="Gaussian sensor noise, standard deviation in 8-bit "
                                      "levels")
    supersample: int | None = option(
        None, "--supersample", type=int, choices=(1, 2, 3, 4),
        help="render s x s samples per pixel (default 1 for ideal cameras, 2 otherwise)")
    encoding: str | None = option(None, "--encoding", choices=("rgb8", "bgr8", "mono8"),
                                  help="image encoding")
    compression: str | None = option(
        None, "--compression", choices=("zstd", "lz4", "bz2", "none"),
        help="compression: MCAP chunks zstd (default), lz4 or none; rosbag2 zstd (MCAP "
             "chunks, default; sqlite3: per message) or none (sqlite3 default); ROS1 chunks "
             "lz4 (default), bz2 or none")
    drift: tuple[dict[str, Any], ...] = option(
        (), "--drift", type=_drift, action="append", metavar="CAMERA:AXIS:DEGREES@S",
        help="turn a camera (its name, e.g. left or right, or namespace) by DEGREES about an "
             "axis of its optical frame (roll: z, pitch: x, yaw: y) from S seconds after the "
             "start on, its camera_info unchanged; repeatable")
    latency: tuple[dict[str, Any], ...] = option(
        (), "--latency", type=_latency, action="append", metavar="CAMERA:MS[@S]",
        help="stamp a camera's messages MS milliseconds after the exposure they carry "
             "(negative: before it), as a driver that stamps late does (from S seconds after "
             "the start on: a driver restarted); exposure times, jitter and drops unchanged; "
             "repeatable")
    progress: bool | None = common.progress()

    def overrides(self) -> dict[str, Any]:
        """The scenario overrides the request names (None: the scenario's own)."""
        out: dict[str, Any] = {
            "seed": self.seed,
            "duration_s": self.duration,
            "frames": self.frames,
            "hfov_rad": self.hfov,
            "noise_std": self.noise,
            "supersample": self.supersample,
            "encoding": self.encoding,
            "drifts": list(self.drift) or None,
            "latencies": list(self.latency) or None,
        }
        if self.resolution:
            out["width"], out["height"] = self.resolution
        if self.intrinsics is not None:
            out["intrinsics"] = list(self.intrinsics)
        if self.distortion:
            out["distortion_model"], out["distortion"] = \
                self.distortion[0], list(self.distortion[1])
        return out
