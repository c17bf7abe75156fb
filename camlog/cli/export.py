"""``camlog export LOG --topic T -o DIR [--format png|jpg|mp4]``: images out of a log.

Like ``image_view``'s ``extract_images``: one file per frame named by its header stamp
(``<stamp_ns>.png``, 19 digits so names sort in time order), 16-bit images (depth) as 16-bit
PNG, or one H.264 MP4 with ``--format mp4`` (PyAV: ``pip install 'camlog[video]'``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .args import add_no_progress, add_overwrite, add_recover, bounded_int


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``export`` arguments."""
    p.add_argument("log", metavar="LOG", type=Path, help="input log (never modified)")
    p.add_argument("--topic", required=True, metavar="T",
                   help="image topic (sensor_msgs/Image or CompressedImage, any encoding)")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                   help="folder for the image files (or the MP4); with --format mp4 a name "
                        "ending in .mp4 is the video itself")
    p.add_argument("--format", choices=("png", "jpg", "mp4"), default=None,
                   help="png (default; 16-bit images stay 16-bit), jpg, or mp4 (one video; "
                        "the default when DIR ends in .mp4)")
    p.add_argument("--every", type=bounded_int(1, None), default=1, metavar="N",
                   help="export every N-th frame")
    p.add_argument("--start", type=float, metavar="S",
                   help="start S seconds after the log's first message")
    p.add_argument("--end", type=float, metavar="S",
                   help="stop S seconds after the log's first message (exclusive)")
    p.add_argument("--jpeg-quality", type=bounded_int(1, 100), default=95, metavar="Q",
                   help="JPEG quality for --format jpg (default 95)")
    add_overwrite(p)
    add_recover(p)
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Export the frames and say where they went."""
    from ..processing.export_images import export_images

    fmt = args.format or ("mp4" if args.output.suffix.lower() == ".mp4" else "png")
    result = export_images(args.log, args.topic, args.output, fmt=fmt, every=args.every,
                           start_s=args.start, end_s=args.end, jpeg_quality=args.jpeg_quality,
                           overwrite=args.overwrite, recover=args.recover,
                           progress=not args.no_progress)
    rate = f" at {result.fps:.2f} fps" if result.fps else ""
    print(f"exported {result.frames} frames of {args.topic}{rate} "
          f"({result.bytes_written / 1e6:.1f} MB)")
    print(f"wrote {result.output}")
    return 0
