"""Names of the log formats and image codecs camlog writes, without loading any library (for
argument parsers: ``--format`` and ``--compress`` choices, defaults)."""

from __future__ import annotations

__all__ = ["DEFAULT_CRF", "STILL_CODECS", "VIDEO_CODEC_NAMES", "WRITE_FORMATS"]

#: ``--format`` names, in the order of :data:`replay.formats.FORMATS`
WRITE_FORMATS = ("mcap", "rosbag2", "rosbag2-sqlite3", "ros1")

#: still-image compressions (``sensor_msgs/CompressedImage`` formats camlog writes)
STILL_CODECS = ("jpeg", "png")

#: video codecs camlog writes (``foxglove.CompressedVideo`` formats)
VIDEO_CODEC_NAMES = ("h264", "h265")

#: the video encoder's constant rate factor by default: 18, x264's "visually lossless", keeps
#: 39-40 dB PSNR on 640x480 images with 2 levels of sensor noise and still shrinks such a
#: log far more than tenfold (``benchmarks.video_size``)
DEFAULT_CRF = 18
