"""``camlog convert IN OUT``: between MCAP, rosbag2 and ROS1, filtered, images re-encoded."""

from __future__ import annotations

import argparse
from pathlib import Path

from replay.atomic import refuse_existing
from replay.format_names import DEFAULT_CRF, STILL_CODECS, VIDEO_CODEC_NAMES

from .args import (
    add_format_argument,
    add_no_progress,
    add_overwrite,
    add_recover,
    add_selection,
    bounded_int,
    output_path,
    print_warnings,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``convert`` arguments."""
    p.epilog = (
        "Messages are copied as stored (byte for byte between CDR formats; ROS1 <-> CDR "
        "re-serialized by rosbags, which drops ROS1's Header.seq; Foxglove protobuf/JSON "
        "channels are copied into MCAP untouched). --compress stores Image topics T as "
        "CompressedImage on T/compressed (jpeg, png) or as foxglove.CompressedVideo on "
        "T/video (h264, h265; MCAP only), --decompress the reverse, as image_transport names "
        "them; topics the format cannot hold losslessly (16-bit, depth) go to PNG or are "
        "copied."
    )
    p.add_argument("input", metavar="IN", type=Path, help="MCAP file, rosbag2 directory or .bag")
    p.add_argument("output", metavar="OUT", type=output_path,
                   help="output log: .mcap, .bag or a directory name (rosbag2)")
    add_format_argument(p, default_from="OUT")
    add_selection(p)
    codec = p.add_mutually_exclusive_group()
    codec.add_argument("--compress", choices=(*STILL_CODECS, *VIDEO_CODEC_NAMES),
                       help="store raw images compressed on TOPIC/compressed")
    codec.add_argument("--decompress", action="store_true",
                       help="store compressed images raw (TOPIC/compressed -> TOPIC)")
    p.add_argument("--crf", type=bounded_int(0, 51), default=DEFAULT_CRF, metavar="N",
                   help="h264/h265: the encoder's constant rate factor, 0-51, lower is better "
                        f"and larger (default {DEFAULT_CRF})")
    p.add_argument("--profile", choices=("ros2", "foxglove"), default="ros2",
                   help="MCAP: store images, camera models and video in Foxglove's schemas "
                        "(foxglove) or ROS 2 messages (ros2, default)")
    add_overwrite(p)
    add_recover(p)
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.convert.convert_log`."""
    refuse_existing(args.output, overwrite=args.overwrite, inputs=[args.input])
    from camlog.logs.convert import convert_log

    result = convert_log(
        args.input, args.output, fmt=args.format, topics=args.topics, start_s=args.start,
        end_s=args.end, compress=args.compress, decompress=args.decompress,
        profile=args.profile, overwrite=args.overwrite, recover=args.recover,
        progress=False if args.no_progress else None, crf=args.crf)
    print(f"converted {result.messages} messages ({result.reencoded} images re-encoded) to "
          f"{result.format_name} in {result.wall_s:.2f} s")
    for before, after in sorted(result.renamed.items()):
        print(f"renamed {before} -> {after}")
    for topic, psnr in sorted(result.psnr_db.items()):
        print(f"{topic}: {args.compress} PSNR {psnr:.1f} dB (mean over its frames)")
    print_warnings(result.warnings)
    print(f"wrote {result.output}")
    return 0
