"""``camlog record``: simulate a scenario and write its camera log."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from recorder.builtin import DEFAULT_SCENARIO, MAX_FRAMES, builtin_names
from replay.atomic import refuse_existing
from replay.format_names import WRITE_FORMATS
from replay.lens_models import LENS_MODELS

from .args import (
    add_no_progress,
    add_overwrite,
    bounded_int,
    non_negative,
    number,
    output_path,
    positive,
)

#: longest recording in seconds and largest image side the command line accepts
MAX_DURATION_S = 86_400.0
MAX_SIDE = 8192
#: distortion model -> number of coefficients
#: MODEL:K1,K2,... for every lens model, as --distortion takes them
DISTORTION_FORMS = [f"{m.name}:{','.join(m.coefficients)}" for m in LENS_MODELS.values()]
#: the axes a camera may drift about (recorder.drift.AXES, without loading the recorder)
DRIFT_AXES = ("roll", "pitch", "yaw")


def _floats(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.replace(" ", "").split(",") if v]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated numbers, got {text!r}"
        ) from None
    if not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values


def _intrinsics(text: str) -> list[float]:
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


def _distortion(text: str) -> tuple[str, list[float]]:
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


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``record`` arguments."""
    p.add_argument("scenario", nargs="?", default=DEFAULT_SCENARIO,
                   help=f"built-in scenario name ({', '.join(builtin_names())}) or path to a "
                        f".toml spec (default: {DEFAULT_SCENARIO})")
    p.add_argument("-o", "--output", type=output_path,
                   help="output log: NAME.mcap (default), NAME.bag (ROS1) or a directory name "
                        "(rosbag2); default: recordings/SCENARIO.mcap")
    p.add_argument("--format", choices=sorted(WRITE_FORMATS),
                   help="output format (default: from the output name; .mcap when none)")
    add_overwrite(p)
    p.add_argument("--seed", type=bounded_int(0, 2**63 - 1),
                   help="random seed (board poses, stamps, noise)")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--duration", type=number(above=0.0, high=MAX_DURATION_S), metavar="S",
                        help=f"recording length in seconds (at most {MAX_DURATION_S:g})")
    length.add_argument("--frames", type=bounded_int(1, MAX_FRAMES), metavar="N",
                        help=f"frames per camera (at most {MAX_FRAMES})")
    p.add_argument("--resolution", type=_resolution, metavar="WxH",
                   help="image size of every camera, e.g. 640x480")
    p.add_argument("--hfov", type=positive, metavar="RAD", help="horizontal field of view (rad)")
    p.add_argument("--intrinsics", type=_intrinsics, metavar="FX,FY,CX,CY",
                   help="pinhole intrinsics in pixels (overrides --hfov)")
    p.add_argument("--distortion", type=_distortion, metavar="MODEL:K1,K2,...",
                   help="lens distortion, e.g. plumb_bob:-0.2,0.05,0,0,0; "
                        f"{', '.join(DISTORTION_FORMS)} (a fisheye model is rendered as "
                        "several views)")
    p.add_argument("--noise", type=non_negative, metavar="SIGMA",
                   help="Gaussian sensor noise, standard deviation in 8-bit levels")
    p.add_argument("--supersample", type=int, choices=(1, 2, 3, 4),
                   help="render s x s samples per pixel (default 1 for ideal cameras, 2 otherwise)")
    p.add_argument("--encoding", choices=("rgb8", "bgr8", "mono8"), help="image encoding")
    p.add_argument("--compression", choices=("zstd", "lz4", "bz2", "none"),
                   help="compression: MCAP chunks zstd (default), lz4 or none; rosbag2 "
                        "zstd (MCAP chunks, default; sqlite3: per message) or none "
                        "(sqlite3 default); ROS1 chunks lz4 (default), bz2 or none")
    p.add_argument("--drift", type=_drift, action="append", metavar="CAMERA:AXIS:DEGREES@S",
                   help="turn a camera (its name, e.g. left or right, or namespace) by DEGREES "
                        "about an axis of its optical frame (roll: z, pitch: x, yaw: y) from S "
                        "seconds after the start on, its camera_info unchanged; repeatable")
    add_no_progress(p)


def overrides_from(args: argparse.Namespace) -> dict[str, Any]:
    """Scenario overrides named by the command line."""
    out: dict[str, Any] = {
        "seed": args.seed,
        "duration_s": args.duration,
        "frames": args.frames,
        "hfov_rad": args.hfov,
        "noise_std": args.noise,
        "supersample": args.supersample,
        "encoding": args.encoding,
        "drifts": args.drift,
    }
    if args.resolution:
        out["width"], out["height"] = args.resolution
    if args.intrinsics is not None:
        out["intrinsics"] = args.intrinsics
    if args.distortion:
        out["distortion_model"], out["distortion"] = args.distortion
    return out


def run(args: argparse.Namespace) -> int:
    """Record the scenario and print what was written."""
    if args.output is not None:  # refused before the scenario loader's libraries load
        refuse_existing(args.output, overwrite=args.overwrite)
    from recorder.scenario import load_scenario

    scenario = load_scenario(args.scenario, overrides_from(args))
    output = args.output or Path("recordings") / f"{scenario.name}.mcap"
    refuse_existing(output, overwrite=args.overwrite)
    from recorder.record import record

    if args.output is None:
        output.parent.mkdir(parents=True, exist_ok=True)
    result = record(scenario, output, fmt=args.format, overwrite=args.overwrite,
                    progress=False if args.no_progress else None,
                    compression=args.compression)
    frames = ", ".join(f"{name} {n}" for name, n in result.frames.items())
    drops = {n: len(d) for n, d in result.dropped.items() if d}
    dropped = f", dropped {drops}" if drops else ""
    print(f"recorded {scenario.name} (seed {scenario.seed}): {frames} frames{dropped} "
          f"in {result.wall_s:.1f} s ({result.fps:.0f} frames/s)")
    for drift in scenario.drifts:
        print(f"drift: {drift.camera} {drift.axis} {drift.degrees:+g}° from {drift.start_s:g} s")
    print(f"wrote {result.path} ({result.storage})")
    return 0
