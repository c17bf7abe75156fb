"""``camlog process LOG --topic T ...``: run image processors over one topic of a log."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any

from processors.registry import make_processor
from processors.throttle import make_throttle
from replay.formats import FORMATS

from ..errors import UsageError
from ..processing.process_log import COMPRESSIONS, process_log


def _rectify_options(args: argparse.Namespace) -> dict[str, Any]:
    from replay.calibration_yaml import load_calibration

    return {"camera_info": load_calibration(args.rectify).camera_info}


#: processor name -> (is it chosen, its options) from the command line
CHOSEN: dict[str, tuple[Callable[[argparse.Namespace], bool],
                        Callable[[argparse.Namespace], dict[str, Any]]]] = {
    "red_pixels": (lambda a: a.red_pixels, lambda a: {"ratio": a.ratio}),
    "edges": (lambda a: a.edges, lambda a: {"low": a.low, "high": a.high}),
    "rectify": (lambda a: a.rectify is not None, _rectify_options),
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``process`` arguments."""
    p.epilog = (
        "Every input message is copied through unchanged (unless --drop-input); outputs carry "
        "the processed frame's header and log time."
    )
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUT",
                   help="output log: .mcap, .bag or a rosbag2 directory name")
    p.add_argument("--topic", required=True, metavar="T",
                   help="image topic to process (Image or CompressedImage, e.g. "
                        "/cam/image_raw or /cam/image_raw/compressed)")
    red = p.add_argument_group("red pixels (the chapter's find_red_pixels)")
    red.add_argument("--red-pixels", action="store_true",
                     help="mask of pixels with R > RATIO*(G+B) with a blue square at their "
                          "centroid -> /image_converter/output_video (rgb8); centroid "
                          "-> /image_converter/red_centroid (PointStamped x=u, y=v px); "
                          "count -> /image_converter/red_count (PointStamped x=count)")
    red.add_argument("--ratio", type=int, default=10, help="redness ratio (default 10)")
    edges = p.add_argument_group("edges (the chapter's find_features)")
    edges.add_argument("--edges", action="store_true",
                       help="grayscale + Canny -> /image_converter/edges (mono8)")
    edges.add_argument("--low", type=float, default=50.0, help="Canny low threshold (50)")
    edges.add_argument("--high", type=float, default=150.0, help="Canny high threshold (150)")
    p.add_argument("--rectify", type=Path, metavar="OST.YAML",
                   help="rectify with a camera_info_manager calibration file "
                        "-> /image_converter/image_rect")
    rate = p.add_mutually_exclusive_group()
    rate.add_argument("--every", type=int, metavar="N", help="process every N-th frame")
    rate.add_argument("--rate", type=float, metavar="HZ",
                      help="process at most HZ frames per second of header stamp (throttle)")
    p.add_argument("--compress", choices=COMPRESSIONS,
                   help="write image outputs as CompressedImage on TOPIC/compressed")
    p.add_argument("--drop-input", "--topics-only", dest="drop_input", action="store_true",
                   help="write only the processors' output topics, not the input's")
    p.add_argument("--max-frames", type=int, metavar="N",
                   help="stop after N frames of the topic (quick runs)")
    p.add_argument("--workers", type=int, metavar="N", help="processing threads (default: cores)")
    p.add_argument("--format", choices=sorted(FORMATS), help="output format (default: from OUT)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")
    p.add_argument("--recover", action="store_true", help="read a damaged log up to the damage")


def run(args: argparse.Namespace) -> int:
    """Build the processors named on the command line and call :func:`process_log`."""
    chosen = [name for name, (is_chosen, _) in CHOSEN.items() if is_chosen(args)]
    if not chosen:
        raise UsageError("choose at least one of --red-pixels, --edges, --rectify")
    processors = [make_processor(name, **CHOSEN[name][1](args)) for name in chosen]
    result = process_log(
        args.log, args.output, topic=args.topic, processors=processors,
        throttle=make_throttle(every=args.every, rate_hz=args.rate), compress=args.compress,
        drop_input=args.drop_input, max_frames=args.max_frames, fmt=args.format,
        overwrite=args.overwrite, workers=args.workers, recover=args.recover,
    )
    print(f"processed {result.frames_processed} of {result.frames_read} frames of {args.topic} "
          f"({', '.join(chosen)}) in {result.wall_s:.2f} s ({result.fps:.0f} frames/s)")
    print(f"wrote {result.output}")
    return 0
