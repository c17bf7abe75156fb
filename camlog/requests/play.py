"""The requests of ``camlog play`` (which logs, how fast, how often, where to) and ``camlog
view`` (which logs, where to, how they are drawn)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from replay.format_names import LOG_TIMES
from rerun_export.options import UNDISTORTED_SCALE

from . import fields as common
from .fields import option
from .values import bounded_int, number, positive

__all__ = ["PlayRequest", "ToViewer", "ViewRequest"]


@dataclass(frozen=True, kw_only=True)
class ToViewer:
    """Where a replay or a recording goes: ``output`` (a file), a spawned viewer listening
    on ``bind:port``, or a running one at ``connect``."""

    output: Path | None = None
    spawn: bool = common.spawn()
    connect: str | None = common.connect()
    bind: str = common.bind()
    port: int = common.port()
    overwrite: bool = common.overwrite()


@dataclass(frozen=True, kw_only=True)
class PlayRequest(ToViewer):
    """Replay logs in (scaled) real time to a viewer, an .rrd or a new log."""

    epilog: ClassVar[str] = (
        "Messages are emitted when due: (log time - first log time) / RATE after the start. "
        "-o OUT.rrd records the replay for rerun (timelines log_time, header_stamp and "
        "replay_time); any other -o OUT is a log that receives the messages as they are "
        "played, bytes and header stamps unchanged, log time = the wall-clock time of "
        "emission (--log-time original keeps the input's). An endless --loop ends with "
        "Ctrl-C, keeping what was played."
    )

    logs: tuple[Path, ...] = option((), metavar="LOG", type=Path, nargs="+", batch=False,
                                    help="log(s) to replay (several are merged in log time)")
    output: Path | None = common.viewer_output("replay (.rrd: rerun recording; else a log)")
    rate: float = option(1.0, "--rate", type=number(low=1e-3, high=1e6), metavar="R",
                         help="speed factor (default 1: real time; 2: twice as fast)")
    topics: tuple[str, ...] | None = common.topics()
    start: float | None = common.start()
    end: float | None = common.end()
    loop: int = option(1, "--loop", nargs="?", const=0, type=bounded_int(1, None),
                       metavar="N", help="replay N times, or until interrupted without N")
    log_time: str = option("replay", "--log-time", choices=LOG_TIMES,
                           help="log time written to a log output (default: replay wall "
                                "clock)")
    format: str | None = common.log_format()
    recover: bool = common.recover()
    progress: bool | None = common.progress()


@dataclass(frozen=True, kw_only=True)
class ViewRequest(ToViewer):
    """Show logs in rerun: write an .rrd or stream to a viewer, with a ready layout."""

    epilog: ClassVar[str] = (
        "Every camera is an entity world/NS with its Pinhole (from camera_info) and images; "
        "a camera whose lens is not a pinhole (distortion, fisheye, a rectified stereo "
        "camera) keeps its raw images and their overlays in raw/NS and gets pinhole views "
        "world/NS/undistorted (wide for a fisheye that sees further, rectified for a stereo "
        "pair) made from them, where the 3D view is true. Beside each Pinhole the camera's "
        "full model (camlog export REC.rrd --calibration writes it back as YAML). "
        "A stereo rig gets its transform from the scenario record or the right camera's "
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

    logs: tuple[Path, ...] = option((), metavar="LOG", type=Path, nargs="+", batch=False,
                                    help="MCAP file, rosbag2 directory or ROS1 .bag")
    output: Path | None = common.viewer_output("recording")
    jpeg_quality: int | None = option(
        None, "--jpeg-quality", type=bounded_int(1, 100), metavar="Q",
        help="store raw 8-bit images as JPEG of quality Q (1-100) in the recording")
    every: int = option(1, "--every", type=bounded_int(1, None), metavar="N",
                        help="keep every N-th image of each camera (and its overlays)")
    topics: tuple[str, ...] | None = common.topics()
    start: float | None = common.start()
    end: float | None = common.end()
    residual_scale: float = option(50.0, "--residual-scale", type=positive, metavar="X",
                                   help="draw calibration residual arrows X times their "
                                        "length (default 50)")
    ground_truth: bool = option(True, "--no-ground-truth", action="store_const", const=False,
                                help="do not project the simulator's target points into the "
                                     "images")
    undistort: bool = option(True, "--no-undistort", action="store_const", const=False,
                             help="make no pinhole views of distorted cameras: their raw "
                                  "images go under a Pinhole of their K, as rerun alone "
                                  "shows them (wrong off the image centre)")
    undistorted_scale: float = option(
        UNDISTORTED_SCALE, "--undistorted-scale", type=number(above=0.0, high=4.0), metavar="S",
        help=f"the pinhole views' width and height, S times the raw image's (default "
             f"{UNDISTORTED_SCALE:g}: a quarter of its pixels; 1 for full size)")
    recover: bool = common.recover()
    progress: bool | None = common.progress()
