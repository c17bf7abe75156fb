"""``camlog import DIR -o LOG``: a folder of image files as a camera log."""

from __future__ import annotations

import argparse
from pathlib import Path

from replay.format_names import DEFAULT_START_NS

from .args import (
    add_format_argument,
    add_no_progress,
    add_overwrite,
    bounded_int,
    name,
    number,
    output_path,
    print_warnings,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``import`` arguments."""
    p.epilog = (
        "Files (.png, .jpg, .jpeg, .ppm, .pgm, .pnm; 8 or 16 bit) are taken in natural order "
        "and stamped START + i/RATE. Colour images become rgb8, grey ones mono8/mono16. "
        "Images go to NS/image_raw under the --camera namespace, as every camlog command "
        "names a camera (--topic is the same option). --stereo pairs left*/right* files with "
        "the same rest of the name into NS/left/image_raw and NS/right/image_raw with "
        "identical stamps."
    )
    p.add_argument("folder", metavar="DIR", type=Path, help="folder of image files")
    p.add_argument("-o", "--output", type=output_path, required=True, metavar="LOG",
                   help="output log: .mcap, .bag or a directory name (rosbag2)")
    p.add_argument("--camera", "--topic", dest="camera", type=name, metavar="NS",
                   help="camera namespace: images on NS/image_raw, camera_info on "
                        "NS/camera_info (default /camera); a raw image topic (NS/image_raw, "
                        "NS/image_rect, NS/image) is taken as it is; with --stereo the rig's "
                        "namespace (default /stereo)")
    p.add_argument("--rate", type=number(above=0.0, high=1e6), default=10.0, metavar="HZ",
                   help="frame rate of the stamps (default 10)")
    p.add_argument("--stereo", action="store_true", help="pair left*/right* files")
    p.add_argument("--camera-info", type=Path, action="append", default=[], metavar="YAML",
                   help="calibration file (camera_info_manager YAML) for the camera_info "
                        "topic; with --stereo give it twice: left, then right")
    p.add_argument("--start-time", type=bounded_int(0, None), default=DEFAULT_START_NS,
                   metavar="NS", help=f"first stamp in ns since the epoch (default "
                                      f"{DEFAULT_START_NS})")
    p.add_argument("--frame-id", type=name, metavar="ID",
                   help="header frame_id (default from the namespace, e.g. "
                        "camera_optical_frame; with --stereo ID_left / ID_right)")
    add_format_argument(p, default_from="LOG")
    add_overwrite(p)
    add_no_progress(p)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.importer.import_images`."""
    from camlog.logs.importer import import_images

    result = import_images(
        args.folder, args.output, camera=args.camera, rate_hz=args.rate, stereo=args.stereo,
        camera_info=args.camera_info, start_ns=args.start_time, frame_id=args.frame_id,
        fmt=args.format, overwrite=args.overwrite,
        progress=False if args.no_progress else None)
    print(f"imported {result.frames} frames per camera to {', '.join(result.topics)} in "
          f"{result.wall_s:.2f} s")
    print_warnings(f"{path} has no stereo partner; skipped" for path in result.skipped)
    print(f"wrote {result.output}")
    return 0
