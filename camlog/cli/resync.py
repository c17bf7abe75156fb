"""``camlog resync LOG -o OUT``: pair and re-stamp two unsynchronised cameras."""

from __future__ import annotations

import argparse
from pathlib import Path

from replay.topics import RESYNC_PREFIX

from .args import add_format_argument, add_overwrite, add_recover, name, number, output_path


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``resync`` arguments."""
    p.epilog = (
        "Pairs: |right - left| <= slop, each frame used once, as many pairs as possible, then "
        "the smallest total stamp difference (ties to the earlier frame). Each pair is "
        "re-stamped with the later of its two stamps and written to "
        "PREFIX/{left,right}/{image_raw,camera_info}; PREFIX/offset_s (PointStamped, x = "
        "right - left in s) per pair and PREFIX/stats (JSON) summarise the pairing. Every "
        "input topic is kept."
    )
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="OUT",
                   help="output log: .mcap, .bag or a rosbag2 directory name")
    p.add_argument("--left", type=name, default="/unsynced/left", metavar="NS",
                   help="left camera namespace with image_raw[/compressed] and camera_info, or "
                        "its image topic (default /unsynced/left)")
    p.add_argument("--right", type=name, default="/unsynced/right", metavar="NS",
                   help="right camera namespace or its image topic (default /unsynced/right)")
    p.add_argument("--slop", type=number(low=0.0, high=3600.0), metavar="SEC",
                   help="largest |right - left| stamp difference of a pair "
                        "(default: half the median frame period)")
    p.add_argument("--out-prefix", type=name, default=RESYNC_PREFIX, metavar="NS",
                   help=f"namespace of the re-stamped topics (default {RESYNC_PREFIX})")
    add_format_argument(p, default_from="OUT")
    add_overwrite(p)
    add_recover(p)


def _stamps(values: list[int]) -> str:
    shown = ", ".join(str(v) for v in values[:10])
    return f" [{shown}{', ...' if len(values) > 10 else ''}]" if values else ""


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.processing.resync_log.resync_log` and print its pairing
    statistics."""
    from ..processing.resync_log import resync_log

    result = resync_log(
        args.log, args.output, left=args.left, right=args.right, out_prefix=args.out_prefix,
        slop_s=args.slop, fmt=args.format, overwrite=args.overwrite, recover=args.recover,
    )
    s = result.stats
    print(f"paired {s.pairs} of {s.left_frames} left / {s.right_frames} right frames "
          f"(slop {s.slop_ns / 1e6:.3f} ms, re-stamped with the later stamp)")
    for side, unpaired in (("left", s.left_unpaired_stamps_ns),
                           ("right", s.right_unpaired_stamps_ns)):
        print(f"unpaired {side}: {len(unpaired)}{_stamps(unpaired)}")
    offset = s.offset_right_minus_left_ns
    if offset is not None:
        print(f"offset right - left: min {offset.min / 1e6:.3f} ms, median "
              f"{offset.median / 1e6:.3f} ms, max {offset.max / 1e6:.3f} ms")
    print(f"wrote {result.output} in {result.wall_s:.2f} s")
    return 0
