"""The well-known topics of camlog logs, named once, and the typed record each one holds.

A camera namespace ``ns`` owns ``{ns}/image_raw[/compressed]`` and ``{ns}/camera_info``; the
simulator adds ``{ns}/ground_truth/{target}`` (``PoseStamped``: the target in the camera's
optical frame) and the log-wide ``/camlog/scenario`` (:class:`~replay.records.Scenario`);
``camlog calibrate`` adds ``{ns}/calibration/{detections,residuals,view_error,uncertainty}``,
``{ns}/calibrated/camera_info``, ``{ns}/image_rect`` (stereo) and ``/calibration/summary``
(:class:`~replay.records.CalibrationSummary`); ``camlog resync`` writes the pairs under a
prefix (default ``/stereo_sync``) with ``{prefix}/offset_s`` and ``{prefix}/stats``
(:class:`~replay.records.ResyncStats`); ``camlog process`` writes its outputs where the user
asks and says what each is on ``/camlog/processed``
(:class:`~replay.records.ProcessedOutputs`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

from .errors import ReplayError

if TYPE_CHECKING:  # the names are light to import; reading a record is not
    from .formats.base import LogReader
    from .records.base import JsonRecord

__all__ = [
    "CALIBRATED_INFO",
    "CALIBRATION_SUMMARY",
    "DETECTIONS",
    "GROUND_TRUTH",
    "IMAGE_RECT",
    "IMAGE_SUFFIXES",
    "PROCESSED",
    "RESIDUALS",
    "RESYNC_PREFIX",
    "SCENARIO",
    "UNCERTAINTY",
    "VIEW_ERROR",
    "CameraTopics",
    "ResyncTopics",
    "camera_of",
    "read_record",
    "split_ground_truth",
]

#: the simulator's scenario record (std_msgs/String, JSON)
SCENARIO = "/camlog/scenario"
#: camlog calibrate's summary (std_msgs/String, JSON)
CALIBRATION_SUMMARY = "/calibration/summary"
#: camlog process's record of what each output topic is (std_msgs/String, JSON; one per run)
PROCESSED = "/camlog/processed"
#: where camlog resync writes the re-stamped pairs by default
RESYNC_PREFIX = "/stereo_sync"

# topic names relative to a camera namespace
IMAGE_RAW = "image_raw"
CAMERA_INFO = "camera_info"
GROUND_TRUTH = "ground_truth"
DETECTIONS = "calibration/detections"
RESIDUALS = "calibration/residuals"
VIEW_ERROR = "calibration/view_error"
UNCERTAINTY = "calibration/uncertainty"
CALIBRATED_INFO = "calibrated/camera_info"
IMAGE_RECT = "image_rect"

#: a camera namespace's image topics, most preferred first: image_transport's names (and
#: ``convert --compress h264``'s), then names Foxglove-style logs use
IMAGE_SUFFIXES = ("image_raw", "image_raw/compressed", "image_raw/video", "image_rect",
                  "image", "image/compressed", "image/video", "compressed", "video")
#: the longest suffix first, so that ``image_raw/compressed`` wins over ``compressed``
_SUFFIXES_LONGEST_FIRST = sorted(IMAGE_SUFFIXES, key=len, reverse=True)


def camera_of(image_topic: str) -> str | None:
    """The camera namespace of an image topic named with one of :data:`IMAGE_SUFFIXES`.

    >>> camera_of("/fisheye/image_raw"), camera_of("/c/image_raw/compressed"), camera_of("/f")
    ('/fisheye', '/c', None)
    """
    for suffix in _SUFFIXES_LONGEST_FIRST:
        if image_topic.endswith(f"/{suffix}"):
            return image_topic.removesuffix(f"/{suffix}") or "/"
    return None


@dataclass(frozen=True)
class CameraTopics:
    """The topics of one camera namespace (``/stereo_camera/left``)."""

    namespace: str

    def _under(self, name: str) -> str:
        return f"{self.namespace.rstrip('/')}/{name}"

    @property
    def image_raw(self) -> str:
        """Raw images (``sensor_msgs/Image``)."""
        return self._under(IMAGE_RAW)

    @property
    def camera_info(self) -> str:
        """The driver's camera model (``sensor_msgs/CameraInfo``)."""
        return self._under(CAMERA_INFO)

    def ground_truth(self, target: str) -> str:
        """The simulator's pose of ``target`` in this camera's optical frame."""
        return self._under(f"{GROUND_TRUTH}/{target}")

    @property
    def detections(self) -> str:
        """Calibration frames with the detected corners drawn (``Image``)."""
        return self._under(DETECTIONS)

    @property
    def residuals(self) -> str:
        """One :class:`~replay.records.ViewResiduals` per used calibration view."""
        return self._under(RESIDUALS)

    @property
    def view_error(self) -> str:
        """Per-view calibration RMS (``PointStamped`` x, px)."""
        return self._under(VIEW_ERROR)

    @property
    def uncertainty(self) -> str:
        """The calibration's projection uncertainty (1 sigma, px) over the image: one
        ``32FC1`` ``Image`` whose pixel ``(i, j)`` of ``rows x cols`` holds the value at the
        camera's pixel ``(j (W - 1) / (cols - 1), i (H - 1) / (rows - 1))``."""
        return self._under(UNCERTAINTY)

    @property
    def calibrated_info(self) -> str:
        """The calibrated camera model (``CameraInfo``)."""
        return self._under(CALIBRATED_INFO)

    @property
    def image_rect(self) -> str:
        """Rectified images of a calibrated stereo camera."""
        return self._under(IMAGE_RECT)


def split_ground_truth(topic: str) -> tuple[str, str] | None:
    """``(namespace, target)`` of a ground-truth topic, None for any other topic.

    >>> split_ground_truth("/stereo_camera/left/ground_truth/board")
    ('/stereo_camera/left', 'board')
    """
    namespace, _, target = topic.rpartition(f"/{GROUND_TRUTH}/")
    return (namespace, target) if namespace and target and "/" not in target else None


@dataclass(frozen=True)
class ResyncTopics:
    """The topics ``camlog resync`` writes under ``prefix``."""

    prefix: str = RESYNC_PREFIX

    @property
    def left(self) -> CameraTopics:
        """The re-stamped left camera."""
        return CameraTopics(f"{self.prefix}/left")

    @property
    def right(self) -> CameraTopics:
        """The re-stamped right camera."""
        return CameraTopics(f"{self.prefix}/right")

    @property
    def offset(self) -> str:
        """One ``PointStamped`` per pair: x = right - left stamp, in seconds."""
        return f"{self.prefix}/offset_s"

    @property
    def stats(self) -> str:
        """The :class:`~replay.records.ResyncStats` record."""
        return f"{self.prefix}/stats"


R = TypeVar("R", bound="JsonRecord")


def read_record(reader: LogReader, topic: str, record: type[R]) -> R | None:
    """The first message of ``topic`` as ``record``; None when the log has no such topic.

    A malformed record raises :class:`~replay.errors.RecordError` naming the log and topic.
    """
    if topic not in reader.topics:
        return None
    for raw in reader.raw_messages([topic]):
        try:
            return record.from_message(reader.decode(raw))
        except ReplayError as err:
            raise type(err)(f"{reader.path}: topic {topic}: {err}") from None
    return None
