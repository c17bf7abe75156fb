"""Typed records for the camera message kinds camlog reads and writes.

Every record carries ``stamp_ns`` (header stamp, integer nanoseconds) and ``frame_id``.
Pixels and matrices are numpy arrays with their shape documented on the field.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from . import msgtypes
from .arrays import ArrayFields, Pixels, PixelShape
from .errors import EncodingError, UnsupportedEncodingError

F64 = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class Image(PixelShape, ArrayFields):
    """Raw image (``sensor_msgs/msg/Image``).

    ``pixels`` is ``(H, W)`` for one-channel encodings and ``(H, W, C)`` otherwise, with the
    dtype the encoding implies (uint8 or uint16), channels in encoding order.
    """

    stamp_ns: int
    frame_id: str
    encoding: str
    pixels: Pixels

    def __post_init__(self) -> None:
        check_pixels(self.encoding, self.pixels)

    @property
    def height(self) -> int:
        """Image height in pixels (a semi-planar YUV buffer has more rows than that)."""
        from .frames.raw import RAW_ENCODINGS

        return RAW_ENCODINGS[self.encoding].image_rows(int(self.pixels.shape[0]))


@dataclass(frozen=True, slots=True)
class CompressedImage:
    """Compressed image (``sensor_msgs/msg/CompressedImage``); ``format`` is e.g. ``jpeg``."""

    stamp_ns: int
    frame_id: str
    format: str
    data: bytes


@dataclass(frozen=True, slots=True)
class CompressedVideo:
    """One frame of a compressed video stream (``foxglove.CompressedVideo``): ``format`` is
    ``h264`` or ``h265``, ``data`` Annex B NAL units decoding to exactly one picture."""

    stamp_ns: int
    frame_id: str
    format: str
    data: bytes


@dataclass(frozen=True, slots=True, eq=False)
class CameraInfo(ArrayFields):
    """Camera model (``sensor_msgs/msg/CameraInfo``), OpenCV conventions.

    ``k`` (3, 3) intrinsics, ``d`` (N,) distortion for ``distortion_model``, ``r`` (3, 3)
    rectification rotation, ``p`` (3, 4) projection of the rectified camera.
    """

    stamp_ns: int
    frame_id: str
    width: int
    height: int
    distortion_model: str
    d: F64
    k: F64
    r: F64 = field(default_factory=lambda: np.eye(3))
    p: F64 = field(default_factory=lambda: np.zeros((3, 4)))
    binning_x: int = 0
    binning_y: int = 0
    roi: tuple[int, int, int, int, bool] = (0, 0, 0, 0, False)

    def __post_init__(self) -> None:
        for name, shape in (("k", (3, 3)), ("r", (3, 3)), ("p", (3, 4))):
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != shape:
                raise ValueError(f"CameraInfo.{name} must have shape {shape}, got {value.shape}")
            object.__setattr__(self, name, value)
        object.__setattr__(self, "d", np.asarray(self.d, dtype=np.float64).reshape(-1))


@dataclass(frozen=True, slots=True, eq=False)
class PoseStamped(ArrayFields):
    """Pose (``geometry_msgs/msg/PoseStamped``) of a child frame in ``frame_id``.

    ``position_m`` (3,); ``orientation_xyzw`` (4,) unit quaternion in ROS order.
    """

    stamp_ns: int
    frame_id: str
    position_m: F64
    orientation_xyzw: F64

    def __post_init__(self) -> None:
        object.__setattr__(self, "position_m", np.asarray(self.position_m, dtype=np.float64))
        object.__setattr__(
            self, "orientation_xyzw", np.asarray(self.orientation_xyzw, dtype=np.float64)
        )


@dataclass(frozen=True, slots=True, eq=False)
class PointStamped(ArrayFields):
    """Point (``geometry_msgs/msg/PointStamped``); ``point`` (3,) in ``frame_id`` units."""

    stamp_ns: int
    frame_id: str
    point: F64

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", np.asarray(self.point, dtype=np.float64))


@dataclass(frozen=True, slots=True)
class Text:
    """Plain string (``std_msgs/msg/String``), used for scenario specs and summaries."""

    data: str


Message = (Image | CompressedImage | CompressedVideo | CameraInfo | PoseStamped | PointStamped
           | Text)

#: typed record -> ROS 2 type name
MSGTYPES: dict[type, str] = {
    Image: msgtypes.IMAGE,
    CompressedImage: msgtypes.COMPRESSED_IMAGE,
    CameraInfo: msgtypes.CAMERA_INFO,
    PoseStamped: msgtypes.POSE_STAMPED,
    PointStamped: msgtypes.POINT_STAMPED,
    Text: msgtypes.STRING,
    # no ROS type: stored as Foxglove protobuf
    CompressedVideo: msgtypes.FOXGLOVE_COMPRESSED_VIDEO,
}


def check_pixels(encoding: str, pixels: Pixels) -> None:
    """Raise :class:`EncodingError` unless ``pixels`` has the dtype and channels of ``encoding``
    (the layouts are :data:`replay.frames.raw.RAW_ENCODINGS`)."""
    from .frames.raw import RAW_ENCODINGS  # the table knows no message type

    raw = RAW_ENCODINGS.get(encoding)
    if raw is None:
        raise UnsupportedEncodingError(f"unsupported image encoding {encoding!r} "
                                       f"(supported: {', '.join(sorted(RAW_ENCODINGS))})")
    shape_ok = pixels.ndim == 2 if raw.channels == 1 else (
        pixels.ndim == 3 and pixels.shape[2] == raw.channels
    )
    if pixels.dtype != raw.dtype or not shape_ok:
        raise EncodingError(
            f"pixels {pixels.dtype}{list(pixels.shape)} do not match encoding {encoding!r} "
            f"({raw.dtype}, {raw.channels} channel(s))"
        )
    raw.image_rows(int(pixels.shape[0]))
