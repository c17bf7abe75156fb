"""``camlog view LOG [LOG...]``: logs as a rerun recording (.rrd) or in a live viewer."""

from __future__ import annotations

import argparse
from pathlib import Path

from .args import (
    add_no_progress,
    add_recover,
    add_selection,
    add_viewer_destination,
    bounded_int,
    positive,
    print_warnings,
)
from .lean import without_pandas


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``view`` arguments."""
    p.epilog = (
        "Every camera is an entity world/NS with its Pinhole (from camera_info) and images; "
        "a stereo rig gets its transform from the scenario record or the right camera's "
        "P[0,3]. Calibration corners and residual arrows, red-pixel masks and centroids, "
        "Canny edges and projected ground truth are drawn on the images they belong to "
        "(processor outputs by frame_id); rectified images, per-view errors, red-pixel "
        "counts and stereo offsets get views of their own. Timelines: log_time and "
        "header_stamp. Related logs (overlapping in time, feeding the same camera: a log and "
        "its processed outputs) are merged in log time (a topic from the first log that has "
        "it); unrelated logs get a recording each (same application id, own timelines), all "
        "in one .rrd. Before writing, view prints the size of the images and suggests "
        "--jpeg-quality when raw ones pass 1 GB. Default output: the first LOG with .rrd "
        "(LOG.rrd beside a rosbag2 folder)."
    )
    p.add_argument("logs", metavar="LOG", type=Path, nargs="+",
                   help="MCAP file, rosbag2 directory or ROS1 .bag")
    add_viewer_destination(p, what="recording")
    p.add_argument("--jpeg-quality", type=bounded_int(1, 100), metavar="Q",
                   help="store raw 8-bit images as JPEG of quality Q (1-100) in the recording")
    p.add_argument("--every", type=bounded_int(1, None), default=1, metavar="N",
                   help="keep every N-th image of each camera (and its overlays)")
    add_selection(p)
    p.add_argument("--residual-scale", type=positive, default=50.0, metavar="X",
                   help="draw calibration residual arrows X times their length (default 50)")
    p.add_argument("--no-ground-truth", action="store_true",
                   help="do not project the simulator's target points into the images")
    add_recover(p)
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Call :func:`rerun_export.view_logs` and print what it logged."""
    from rerun_export.paths import refuse_output

    refuse_output(args.logs, args.output, live=args.spawn or args.connect is not None,
                  overwrite=args.overwrite)
    if getattr(args, "as_program", False):
        without_pandas()
    from rerun_export import LoggerOptions, view_logs

    options = LoggerOptions(every=args.every, jpeg_quality=args.jpeg_quality,
                            residual_scale=args.residual_scale,
                            ground_truth=not args.no_ground_truth)
    result = view_logs(
        args.logs, output=args.output, spawn=args.spawn, connect=args.connect,
        bind=args.bind, port=args.port,
        overwrite=args.overwrite, topics=args.topics, start_s=args.start, end_s=args.end,
        options=options, recover=args.recover, progress=False if args.no_progress else None,
        say=print)
    images = sum(n for entity, n in result.counts.items() if entity.endswith("/image"))
    print(f"logged {result.messages} messages ({images} images, {len(result.cameras)} cameras: "
          f"{', '.join(result.cameras) or 'none'}) in {result.wall_s:.2f} s")
    if result.recordings > 1:
        print(f"{result.recordings} recordings: the logs are unrelated (no shared camera at a "
              "shared time), each keeps its own timeline")
    for topic, why in sorted(result.skipped.items()):
        print(f"not shown: {topic}: {why}")
    if result.duplicates:
        shown = ", ".join(result.duplicates[:3]) + (", ..." if len(result.duplicates) > 3 else "")
        print(f"{len(result.duplicates)} topics repeated by a later log were read from the "
              f"first: {shown}")
    print_warnings(result.warnings)
    print(f"wrote {result.output}" if result.output else "sent to the viewer")
    return 0
