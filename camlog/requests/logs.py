"""The requests of the commands that read, copy or write logs whole: ``info``, ``convert``,
``export`` (images out of a log) and ``import`` (images into a log)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from replay.format_names import DEFAULT_CRF, DEFAULT_START_NS, STILL_CODECS, VIDEO_CODEC_NAMES
from replay.storage import Location

from . import fields as common
from .fields import RequestError, option
from .values import bounded_int, name, number, output_path

__all__ = ["ConvertRequest", "ExportRequest", "ImportRequest", "InfoRequest"]


@dataclass(frozen=True, kw_only=True)
class InfoRequest:
    """Summarise a log (or list the temporary outputs unfinished runs left in a folder)."""

    log: Location = common.input_log(
        "MCAP file, rosbag2 directory or ROS1 .bag; or a folder, to list the temporary outputs "
        "that unfinished camlog runs left in it")
    recover: bool = common.recover()
    verify: bool = option(False, "--verify", action="store_true",
                          help="read every message (checksums included) instead of the log's "
                               "index, so that damage anywhere is found")
    progress: bool | None = common.progress()


@dataclass(frozen=True, kw_only=True)
class ConvertRequest:
    """Convert a log between MCAP, rosbag2 and ROS1, filtered, images re-encoded."""

    epilog: ClassVar[str] = (
        "Messages are copied as stored (byte for byte between CDR formats; ROS1 <-> CDR "
        "re-serialized by rosbags, which drops ROS1's Header.seq; Foxglove protobuf/JSON "
        "channels are copied into MCAP untouched). --compress stores Image topics T as "
        "CompressedImage on T/compressed (jpeg, png) or as foxglove.CompressedVideo on "
        "T/video (h264, h265; MCAP only), --decompress the reverse, as image_transport names "
        "them; topics the format cannot hold losslessly (16-bit, depth) go to PNG or are "
        "copied."
    )

    input: Location = option(Path(), metavar="IN", type=Path, batch=False,
                             help="MCAP file, rosbag2 directory or .bag")
    output: Path = option(Path(), metavar="OUT", type=output_path, batch=False,
                          help="output log: .mcap, .bag or a directory name (rosbag2)")
    format: str | None = common.log_format(batch=True)
    topics: tuple[str, ...] | None = common.topics()
    start: float | None = common.start()
    end: float | None = common.end()
    compress: str | None = option(None, "--compress", choices=(*STILL_CODECS,
                                                               *VIDEO_CODEC_NAMES),
                                  exclusive="codec",
                                  help="store raw images compressed on TOPIC/compressed")
    decompress: bool = option(False, "--decompress", action="store_true", exclusive="codec",
                              help="store compressed images raw (TOPIC/compressed -> TOPIC)")
    crf: int = option(DEFAULT_CRF, "--crf", type=bounded_int(0, 51), metavar="N",
                      help=f"h264/h265: the encoder's constant rate factor, 0-51, lower is "
                           f"better and larger (default {DEFAULT_CRF})")
    profile: str = option("ros2", "--profile", choices=("ros2", "foxglove"),
                          help="MCAP: store images, camera models and video in Foxglove's "
                               "schemas (foxglove) or ROS 2 messages (ros2, default)")
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    progress: bool | None = common.progress()


@dataclass(frozen=True, kw_only=True)
class ExportRequest:
    """Write the images of a topic as PNG/JPEG files named by stamp, or one MP4; or the
    camera models of a rerun recording as calibration files."""

    epilog: ClassVar[str] = (
        "--calibration reads a rerun recording (.rrd) that camlog view wrote: every camera's "
        "model (distortion model, D, K, R, P, size), as logged beside its Pinhole, becomes a "
        "camera_info_manager YAML file in DIR named after the camera (stereo/left -> "
        "stereo_left.yaml), every number as it was in the log. A Foxglove kannala_brandt "
        "model is written as ROS's equidistant (the same k1..k4)."
    )

    log: Location = common.input_log("input log (never modified); with --calibration a rerun "
                                     "recording (.rrd)")
    topic: str | None = option(None, "--topic", metavar="T",
                               help="image topic (sensor_msgs/Image or CompressedImage, any "
                                    "encoding)")
    calibration: bool = option(False, "--calibration", action="store_true", batch=False,
                               help="write the camera models of a rerun recording (.rrd) "
                                    "as calibration YAML files instead")
    output: Path = common.output(
        "folder for the image files (or the MP4; the calibration files); with --format mp4 a "
        "name ending in .mp4 is the video itself", metavar="DIR", checked=False)
    format: str | None = option(None, "--format", choices=("png", "jpg", "mp4"),
                                help="png (default; 16-bit images stay 16-bit), jpg, or mp4 "
                                     "(one video; the default when DIR ends in .mp4)")
    every: int = option(1, "--every", type=bounded_int(1, None), metavar="N",
                        help="export every N-th frame")
    start: float | None = option(None, "--start", type=float, metavar="S",
                                 help="start S seconds after the log's first message")
    end: float | None = option(None, "--end", type=float, metavar="S",
                               help="stop S seconds after the log's first message (exclusive)")
    jpeg_quality: int = option(95, "--jpeg-quality", type=bounded_int(1, 100), metavar="Q",
                               help="JPEG quality for --format jpg (default 95)")
    overwrite: bool = common.overwrite()
    recover: bool = common.recover()
    progress: bool = common.progress(True)

    def __post_init__(self) -> None:
        if (self.topic is None) == (not self.calibration):
            raise RequestError(ExportRequest, "give {topic} (the images of a log) or "
                                              "{calibration} (the camera models of a .rrd)")

    @property
    def file_format(self) -> str:
        """``format``, or mp4 for an output named .mp4, else png."""
        return self.format or ("mp4" if self.output.suffix.lower() == ".mp4" else "png")


@dataclass(frozen=True, kw_only=True)
class ImportRequest:
    """Turn a folder of image files (mono or left/right stereo), or camera_calibration's
    archive, into a log."""

    epilog: ClassVar[str] = (
        "Files (.png, .jpg, .jpeg, .ppm, .pgm, .pnm; 8 or 16 bit) are taken in natural order "
        "and stamped START + i/RATE. Colour images become rgb8, grey ones mono8/mono16. "
        "Images go to NS/image_raw under the --camera namespace, as every camlog command "
        "names a camera (--topic is the same option). --stereo pairs left*/right* files with "
        "the same rest of the name into NS/left/image_raw and NS/right/image_raw with "
        "identical stamps. ROS camera_calibration's archive (calibrationdata.tar.gz) is read "
        "as it is: its left-NNNN images (and right-NNNN, a pair) in number order, its own "
        "calibration (ost.yaml, left.yaml and right.yaml, or ost.txt) as the camera_info."
    )

    folder: Path = option(Path(), metavar="DIR", type=Path, batch=False,
                          help="folder of image files, or camera_calibration's archive "
                               "(calibrationdata.tar.gz)")
    output: Path = common.output(metavar="LOG")
    camera: str | None = option(
        None, "--camera", "--topic", type=name, metavar="NS",
        help="camera namespace: images on NS/image_raw, camera_info on NS/camera_info "
             "(default /camera); a raw image topic (NS/image_raw, NS/image_rect, NS/image) is "
             "taken as it is; with --stereo the rig's namespace (default /stereo)")
    rate: float = option(10.0, "--rate", type=number(above=0.0, high=1e6), metavar="HZ",
                         help="frame rate of the stamps (default 10)")
    stereo: bool = option(False, "--stereo", action="store_true",
                          help="pair left*/right* files")
    camera_info: tuple[Path, ...] = option(
        (), "--camera-info", type=Path, action="append", metavar="YAML",
        help="calibration file (camera_info_manager YAML) for the camera_info topic; with "
             "--stereo give it twice: left, then right")
    start_time: int = option(DEFAULT_START_NS, "--start-time", type=bounded_int(0, None),
                             metavar="NS", help=f"first stamp in ns since the epoch (default "
                                                f"{DEFAULT_START_NS})")
    frame_id: str | None = option(
        None, "--frame-id", type=name, metavar="ID",
        help="header frame_id (default from the namespace, e.g. camera_optical_frame; with "
             "--stereo ID_left / ID_right)")
    format: str | None = common.log_format("LOG")
    overwrite: bool = common.overwrite()
    progress: bool | None = common.progress()
