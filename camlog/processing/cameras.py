"""A camera named on the command line, found in a log: by its namespace or by its image topic.

``/fisheye`` names the camera whose images are ``/fisheye/image_raw`` (or another of
:data:`~replay.topics.IMAGE_SUFFIXES`); ``/fisheye/image_raw`` names the same
camera by its image topic, and an image topic with no such suffix (``/fisheye`` itself, as
a log written elsewhere may have it) is a camera of its own, its camera_info beside it.
"""

from __future__ import annotations

from dataclasses import dataclass

from replay.formats import LogReader
from replay.messages import CameraInfo
from replay.msgtypes import RECORD_KINDS, normalize_msgtype
from replay.topics import IMAGE_SUFFIXES, camera_of

from ..errors import InputError
from .checks import IMAGE_TYPES, camera_info_topic

__all__ = ["CameraSource", "cameras_in", "find_camera", "first_camera_info", "image_suffix"]

#: an image topic's suffix by its message type, for an image topic named without one
_SUFFIX_BY_KIND = {"CompressedImage": "image_raw/compressed", "CompressedVideo": "image_raw/video"}


@dataclass(frozen=True)
class CameraSource:
    """The topics of one camera in a log."""

    namespace: str
    image_topic: str
    info_topic: str | None

    @property
    def name(self) -> str:
        """A file-name friendly name: ``/stereo/left`` -> ``stereo_left``."""
        return self.namespace.strip("/").replace("/", "_") or "camera"


def image_suffix(source: CameraSource, msgtype: str) -> str:
    """The suffix of the camera's image topic below its namespace: the topic's own, or for
    a bare image topic the one image_transport gives its message type (``image_raw``,
    ``image_raw/compressed``, ``image_raw/video``)."""
    prefix = source.namespace.rstrip("/") + "/"
    if source.image_topic.startswith(prefix):
        return source.image_topic.removeprefix(prefix)
    return _SUFFIX_BY_KIND.get(RECORD_KINDS.get(normalize_msgtype(msgtype), ""), "image_raw")


def find_camera(reader: LogReader, camera: str) -> CameraSource:
    """The image and camera_info topics of ``camera``: a camera namespace (its image topic
    the first of :data:`IMAGE_SUFFIXES` with messages) or an image topic of the log (its
    camera the namespace above a known suffix, else the topic's own or the one above it,
    whichever has a camera_info). Fails naming the cameras the log has."""
    ns = camera.rstrip("/") or "/"
    base = ns.rstrip("/")
    for topic in (f"{base}/{suffix}" for suffix in IMAGE_SUFFIXES):
        if _is_images(reader, topic):
            return CameraSource(ns, topic, camera_info_topic(reader, ns))
    if _is_images(reader, ns):
        namespace = camera_of(ns)
        if namespace is not None:
            return CameraSource(namespace, ns, camera_info_topic(reader, namespace))
        for candidate in (ns, ns.rpartition("/")[0] or "/"):
            info = camera_info_topic(reader, candidate.rstrip("/"))
            if info is not None:
                return CameraSource(candidate, ns, info)
        return CameraSource(ns, ns, None)
    cameras = [f"{namespace} ({topic})" for namespace, topic in cameras_in(reader)]
    raise InputError(
        f"{reader.path}: no images under camera {ns} (expected {base}/image_raw or "
        f"{base}/image_raw/compressed, or an image topic; cameras, by namespace (image "
        f"topic), either of which names one: {', '.join(cameras) or 'none'})"
    )


def cameras_in(reader: LogReader) -> list[tuple[str, str]]:
    """(namespace, image topic) of every image topic with messages, by namespace: a topic
    with one of camlog's image suffixes under its namespace, any other as its own camera."""
    return sorted((camera_of(topic) or topic, topic) for topic in reader.topics
                  if _is_images(reader, topic))


def _is_images(reader: LogReader, topic: str) -> bool:
    info = reader.topics.get(topic)
    return info is not None and info.count > 0 and info.msgtype in IMAGE_TYPES


def first_camera_info(reader: LogReader, source: CameraSource) -> CameraInfo | None:
    """The first camera_info of a camera (None: it has no camera_info topic, or its first
    message is not one)."""
    if source.info_topic is None:
        return None
    for raw in reader.raw_messages([source.info_topic]):
        message = reader.decode(raw)
        return message if isinstance(message, CameraInfo) else None
    return None
