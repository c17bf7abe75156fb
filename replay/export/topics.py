"""What each topic of a camlog log is, from its name and type alone.

Cameras own ``{ns}/image_raw[/compressed]`` and ``{ns}/camera_info``; the calibration adds
``{ns}/calibration/...`` and ``{ns}/calibrated/camera_info``; processors write under
``/image_converter/...`` with the source image's ``frame_id``, which is how their outputs
find the camera they belong to (``Route.by_frame``).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .. import topics as names
from ..topics import ResyncTopics

__all__ = ["Kind", "Route", "classify"]

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
POINT = "geometry_msgs/msg/PointStamped"
POSE = "geometry_msgs/msg/PoseStamped"
STRING = "std_msgs/msg/String"

PROCESSOR_NS = "/image_converter"


class Kind(Enum):
    """How a topic is shown."""

    IMAGE = "image"  # the camera's own images
    CAMERA_INFO = "camera_info"  # Pinhole (and the stereo baseline)
    CALIBRATED_INFO = "calibrated_info"  # Pinhole when the camera has no camera_info
    RECTIFIED = "rectified"  # a rectified image, shown in its own view
    DETECTIONS = "detections"  # calibration image with the drawn corners
    RESIDUALS = "residuals"  # calibration corners and residual arrows (JSON)
    VIEW_ERROR = "view_error"  # per-view calibration RMS (PointStamped x, px)
    RED_MASK = "red_mask"  # red-pixel mask with the centroid square (rgb8)
    RED_CENTROID = "red_centroid"  # PointStamped x = u, y = v (px)
    RED_COUNT = "red_count"  # PointStamped x = count
    EDGES = "edges"  # Canny edges (mono8)
    GROUND_TRUTH = "ground_truth"  # target pose in the camera optical frame
    STEREO_OFFSET = "stereo_offset"  # PointStamped x = right - left stamp (s)
    POINT_SERIES = "point_series"  # any other PointStamped: x, y, z as time series
    TEXT = "text"  # any other String: a text document
    SKIPPED = "skipped"  # a type camlog does not show


@dataclass(frozen=True, slots=True)
class Route:
    """Where a topic goes: its kind, the camera namespace it names (if any), and whether
    the camera must be found from each message's ``frame_id`` instead. ``detail`` is the
    target name for ground truth."""

    kind: Kind
    namespace: str = ""
    by_frame: bool = False
    detail: str = ""


#: processor topics (image topics without ``/compressed``); their camera is found by frame
BY_FRAME: dict[str, Kind] = {
    f"{PROCESSOR_NS}/output_video": Kind.RED_MASK,
    f"{PROCESSOR_NS}/edges": Kind.EDGES,
    f"{PROCESSOR_NS}/image_rect": Kind.RECTIFIED,
    f"{PROCESSOR_NS}/red_centroid": Kind.RED_CENTROID,
    f"{PROCESSOR_NS}/red_count": Kind.RED_COUNT,
}
#: type -> (suffix, kind) tried in order; the camera namespace is what precedes the suffix
SUFFIXES: dict[str, tuple[tuple[str, Kind], ...]] = {
    IMAGE: ((f"/{names.DETECTIONS}", Kind.DETECTIONS), (f"/{names.IMAGE_RECT}", Kind.RECTIFIED),
            (f"/{names.IMAGE_RAW}", Kind.IMAGE)),
    CAMERA_INFO: ((f"/{names.CALIBRATED_INFO}", Kind.CALIBRATED_INFO),
                  (f"/{names.CAMERA_INFO}", Kind.CAMERA_INFO)),
    POINT: ((f"/{names.VIEW_ERROR}", Kind.VIEW_ERROR),
            (ResyncTopics("").offset, Kind.STEREO_OFFSET)),
    STRING: ((f"/{names.RESIDUALS}", Kind.RESIDUALS),),
}
#: type -> kind of a topic no suffix names (its namespace is the topic itself)
FALLBACK: dict[str, Kind] = {
    IMAGE: Kind.IMAGE, CAMERA_INFO: Kind.CAMERA_INFO, POINT: Kind.POINT_SERIES,
    STRING: Kind.TEXT,
}


def classify(topic: str, msgtype: str) -> Route:
    """The route of one topic.

    >>> classify("/stereo_camera/left/image_raw/compressed", COMPRESSED)
    Route(kind=<Kind.IMAGE: 'image'>, namespace='/stereo_camera/left', by_frame=False, detail='')
    >>> classify("/image_converter/red_centroid", POINT).by_frame
    True
    """
    name = topic
    if msgtype == COMPRESSED:
        msgtype, name = IMAGE, topic.removesuffix("/compressed") or topic
    if msgtype == POSE:
        truth = names.split_ground_truth(topic)
        return Route(Kind.GROUND_TRUTH, truth[0], detail=truth[1]) if truth \
            else Route(Kind.SKIPPED)
    if msgtype not in FALLBACK:
        return Route(Kind.SKIPPED)
    if name in BY_FRAME:
        return Route(BY_FRAME[name], by_frame=True)
    for suffix, kind in SUFFIXES[msgtype]:
        if name.endswith(suffix) and len(name) > len(suffix):
            return Route(kind, name[: -len(suffix)])
    return Route(FALLBACK[msgtype], name)
