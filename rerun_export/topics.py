"""What each topic of a camlog log is: from the log's record of processed outputs, else
from its name and type alone.

Cameras own ``{ns}/image_raw[/compressed]`` and ``{ns}/camera_info``; the calibration adds
``{ns}/calibration/...`` and ``{ns}/calibrated/camera_info``. ``camlog process`` records
each output it writes (:class:`replay.records.ProcessedOutputs`): its source image topic
names the camera and its display (:class:`replay.display.Display`) says how to draw it.
Logs without that record are routed by name: the chapter's ``/image_converter/...``
outputs carry the source image's ``frame_id``, which is how they find the camera they
belong to (``Route.by_frame``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from replay import topics as names
from replay.display import Display
from replay.msgtypes import (
    CAMERA_INFO,
    COMPRESSED_IMAGE,
    FOXGLOVE_COMPRESSED_VIDEO,
    IMAGE,
    POINT_STAMPED,
    POSE_STAMPED,
    STRING,
)
from replay.topics import ResyncTopics
from replay.wire import record_msgtype

if TYPE_CHECKING:
    from replay.records import ProcessedOutput

__all__ = ["Kind", "Route", "classify", "route_output"]

PROCESSOR_NS = "/image_converter"


class Kind(Enum):
    """How a topic is shown."""

    IMAGE = "image"  # the camera's own images
    CAMERA_INFO = "camera_info"  # Pinhole (and the stereo baseline)
    CALIBRATED_INFO = "calibrated_info"  # Pinhole when the camera has no camera_info
    RECTIFIED = "rectified"  # a rectified image, shown in its own view
    DETECTIONS = "detections"  # calibration image with the drawn corners
    RESIDUALS = "residuals"  # calibration corners and residual arrows (JSON)
    UNCERTAINTY = "uncertainty"  # the calibration's projection uncertainty map (32FC1)
    VIEW_ERROR = "view_error"  # per-view calibration RMS (PointStamped x, px)
    PROCESSED_IMAGE = "processed_image"  # a processor's image, shown in its own view
    MASK = "mask"  # a processor's mask (mono8, or rgb8 with a blue marker) over the camera
    POINT_2D = "point_2d"  # a processor's PointStamped x = u, y = v (px) on the camera
    SCALAR = "scalar"  # a processor's PointStamped x as a time series
    EDGES = "edges"  # a processor's edge image (mono8) over the camera
    GROUND_TRUTH = "ground_truth"  # target pose in the camera optical frame
    STEREO_OFFSET = "stereo_offset"  # PointStamped x = right - left stamp (s)
    POINT_SERIES = "point_series"  # any other PointStamped: x, y, z as time series
    TEXT = "text"  # any other String: a text document
    SKIPPED = "skipped"  # a type camlog does not show


@dataclass(frozen=True, slots=True)
class Route:
    """Where a topic goes: its kind, the camera namespace it names (if any), and whether
    the camera must be found from each message's ``frame_id`` instead. ``detail`` is the
    target name for ground truth; a processor's output has the ``entity`` it is drawn at
    under its camera (the series name of a scalar) and a ``label``."""

    kind: Kind
    namespace: str = ""
    by_frame: bool = False
    detail: str = ""
    entity: str = ""
    label: str = ""


#: how each display of a processor output is routed
DISPLAY_KINDS: dict[Display, Kind] = {
    Display.IMAGE: Kind.PROCESSED_IMAGE, Display.RECTIFIED: Kind.RECTIFIED,
    Display.MASK: Kind.MASK, Display.EDGES: Kind.EDGES, Display.POINT_2D: Kind.POINT_2D,
    Display.SCALAR: Kind.SCALAR, Display.POINT_SERIES: Kind.POINT_SERIES,
}

#: the chapter's processor topics in logs without a record (image topics without
#: ``/compressed``); their camera is found by frame
BY_FRAME: dict[str, Route] = {
    f"{PROCESSOR_NS}/output_video": Route(Kind.MASK, by_frame=True, entity="red_pixels/mask",
                                          label="red pixels"),
    f"{PROCESSOR_NS}/edges": Route(Kind.EDGES, by_frame=True, entity="edges",
                                   label="Canny edges"),
    f"{PROCESSOR_NS}/image_rect": Route(Kind.RECTIFIED, by_frame=True, label="rectified"),
    f"{PROCESSOR_NS}/red_centroid": Route(Kind.POINT_2D, by_frame=True,
                                          entity="red_pixels/centroid", label="red centroid"),
    f"{PROCESSOR_NS}/red_count": Route(Kind.SCALAR, by_frame=True, entity="red_pixel_count",
                                       label="red pixel count"),
}
#: type -> (suffix, kind) tried in order; the camera namespace is what precedes the suffix
SUFFIXES: dict[str, tuple[tuple[str, Kind], ...]] = {
    IMAGE: ((f"/{names.DETECTIONS}", Kind.DETECTIONS),
            (f"/{names.UNCERTAINTY}", Kind.UNCERTAINTY),
            (f"/{names.IMAGE_RECT}", Kind.RECTIFIED),
            (f"/{names.IMAGE_RAW}", Kind.IMAGE), ("/image", Kind.IMAGE)),
    CAMERA_INFO: ((f"/{names.CALIBRATED_INFO}", Kind.CALIBRATED_INFO),
                  (f"/{names.CAMERA_INFO}", Kind.CAMERA_INFO), ("/calibration", Kind.CAMERA_INFO)),
    POINT_STAMPED: ((f"/{names.VIEW_ERROR}", Kind.VIEW_ERROR),
                    (ResyncTopics("").offset, Kind.STEREO_OFFSET)),
    STRING: ((f"/{names.RESIDUALS}", Kind.RESIDUALS),),
}
#: type -> kind of a topic no suffix names (its namespace is the topic itself)
FALLBACK: dict[str, Kind] = {
    IMAGE: Kind.IMAGE, CAMERA_INFO: Kind.CAMERA_INFO, POINT_STAMPED: Kind.POINT_SERIES,
    STRING: Kind.TEXT,
}


def route_output(output: ProcessedOutput) -> Route | None:
    """The route of a recorded processor output: drawn on the camera of its source image
    (a point series on its own); None for a display this camlog does not know."""
    display = output.shown_as
    if display is None:
        return None
    kind = DISPLAY_KINDS[display]
    source = output.source.removesuffix("/compressed") or output.source
    namespace = output.topic if kind is Kind.POINT_SERIES else source.rpartition("/")[0]
    return Route(kind, namespace, entity=output.entity, label=output.label)


def classify(topic: str, msgtype: str,
             outputs: Mapping[str, ProcessedOutput] | None = None) -> Route:
    """The route of one topic, from the recorded ``outputs`` (topic -> output) first.

    >>> classify("/stereo_camera/left/image_raw/compressed", COMPRESSED_IMAGE).namespace
    '/stereo_camera/left'
    >>> classify("/image_converter/red_centroid", POINT_STAMPED).by_frame
    True
    """
    route = route_output(outputs[topic]) if outputs and topic in outputs else None
    return route or _by_name(topic, msgtype)


def _by_name(topic: str, msgtype: str) -> Route:
    name = topic
    msgtype = record_msgtype(msgtype)  # Foxglove camera schemas show as their ROS kinds
    if msgtype == COMPRESSED_IMAGE:
        msgtype, name = IMAGE, topic.removesuffix("/compressed") or topic
    elif msgtype == FOXGLOVE_COMPRESSED_VIDEO:
        msgtype, name = IMAGE, topic.removesuffix("/video") or topic
    if msgtype == POSE_STAMPED:
        truth = names.split_ground_truth(topic)
        return Route(Kind.GROUND_TRUTH, truth[0], detail=truth[1]) if truth \
            else Route(Kind.SKIPPED)
    if msgtype not in FALLBACK:
        return Route(Kind.SKIPPED)
    if name in BY_FRAME:
        return BY_FRAME[name]
    for suffix, kind in SUFFIXES[msgtype]:
        if name.endswith(suffix) and len(name) > len(suffix):
            return Route(kind, name[: -len(suffix)])
    return Route(FALLBACK[msgtype], name)
