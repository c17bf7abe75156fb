"""Names and defaults that argument parsers offer, without loading any library: the log
formats and image codecs camlog writes, replay's log times and the first stamp of an import
(``--format``, ``--compress`` choices). The lens models are
:data:`replay.lens_models.LENS_MODELS`."""

from __future__ import annotations

__all__ = ["DEFAULT_CRF", "DEFAULT_START_NS", "LOG_TIMES", "STILL_CODECS", "VIDEO_CODEC_NAMES",
           "WRITE_FORMATS"]

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

#: what ``camlog play`` writes as a message's log time: the replay's wall clock or the log's
LOG_TIMES = ("replay", "original")

#: an import's first stamp by default, the recorder's (2023-11-14T22:13:20Z): imports are
#: deterministic
DEFAULT_START_NS = 1_700_000_000_000_000_000
