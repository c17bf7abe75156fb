"""Pure conversions from camlog's processor and calibration outputs to drawable arrays.

Segmentation classes are shared by every overlay so that one annotation context colours
them all: see :data:`CLASSES`.
"""

from __future__ import annotations

import math
import struct

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.geometry import rotation_from_quat_xyzw
from replay.messages import F64

__all__ = [
    "CLASSES",
    "edge_classes",
    "header_stamp_ns",
    "inside_image",
    "mask_classes",
    "project_target",
    "stamp_free_key",
    "stamp_free_view",
    "target_in_camera",
]

U8 = npt.NDArray[np.uint8]

BACKGROUND, MASK_PIXEL, CENTROID_MARKER, EDGE = 0, 1, 2, 3
#: class id -> (label, RGBA); class 0 is transparent so overlays show the image beneath
CLASSES: dict[int, tuple[str, tuple[int, int, int, int]]] = {
    BACKGROUND: ("background", (0, 0, 0, 0)),
    MASK_PIXEL: ("mask pixel", (255, 40, 40, 255)),
    CENTROID_MARKER: ("centroid marker", (40, 90, 255, 255)),
    EDGE: ("Canny edge", (40, 255, 90, 255)),
}


def mask_classes(mask_rgb: U8) -> U8:
    """``(H, W)`` class ids of a mask as RGB: white (or any bright red) -> mask pixel, blue
    -> marker (the red-pixel output's centroid square); a mono8 mask converted to RGB
    classifies by its brightness.

    Thresholds at half range, so a JPEG-compressed mask classifies the same.

    >>> mask = np.zeros((1, 3, 3), np.uint8); mask[0, 1] = 255; mask[0, 2] = (0, 0, 255)
    >>> mask_classes(mask).tolist()
    [[0, 1, 2]]
    """
    red = mask_rgb[..., 0] > 127
    blue = mask_rgb[..., 2] > 127
    classes = np.where(red, MASK_PIXEL, np.where(blue, CENTROID_MARKER, BACKGROUND))
    return classes.astype(np.uint8)


def edge_classes(edges_mono: U8) -> U8:
    """``(H, W)`` class ids of a Canny edge image (edge where the value is above 127)."""
    return np.where(edges_mono > 127, EDGE, BACKGROUND).astype(np.uint8)


def target_in_camera(points_in_target: F64, *, position_m: F64, orientation_xyzw: F64) -> F64:
    """The target points ``(M, 3)`` in the camera optical frame, given the target's pose in
    it: ``p_camera = R(q) p_target + t`` (none for a quaternion that is not one)."""
    norm = float(np.linalg.norm(orientation_xyzw))
    if not math.isfinite(norm) or norm == 0:
        return np.zeros((0, 3))
    camera_from_target = rotation_from_quat_xyzw(np.asarray(orientation_xyzw) / norm)
    return np.asarray(points_in_target @ camera_from_target.T + np.asarray(position_m))


def project_target(
    points_in_target: F64, *, position_m: F64, orientation_xyzw: F64, model: CameraModel
) -> F64:
    """Pixels ``(M, 2)`` of the target points in front of the camera, given the target's
    pose in the camera optical frame: ``p_camera = R(q) p_target + t``."""
    points_in_camera = target_in_camera(points_in_target, position_m=position_m,
                                        orientation_xyzw=orientation_xyzw)
    in_front = points_in_camera[:, 2] > 1e-6
    if not np.any(in_front):
        return np.zeros((0, 2))
    return model.project(points_in_camera[in_front])


def inside_image(uv: F64, width: int, height: int) -> F64:
    """The pixels ``(N, 2)`` that fall on a ``width`` x ``height`` image (centres at
    integer coordinates, so the image spans -0.5 .. W - 0.5).

    >>> inside_image(np.array([[0.0, 0.0], [-1.0, 2.0], [9.4, 4.0], [3.0, 4.6]]), 10, 5)
    array([[0. , 0. ],
           [9.4, 4. ]])
    """
    keep = ((uv[:, 0] >= -0.5) & (uv[:, 0] <= width - 0.5)
            & (uv[:, 1] >= -0.5) & (uv[:, 1] <= height - 0.5))
    return uv[keep]


#: bytes before the first field after a std_msgs/Header's stamp: CDR's 4-byte encapsulation
#: header or ROS1's seq, then sec and nanosec
_STAMP_END = 12


def stamp_free_key(data: bytes | memoryview) -> bytes:
    """Serialized message minus its header stamp (CDR or ROS1, header first): two
    camera_info messages with equal keys differ only in their stamp."""
    return bytes(data[_STAMP_END:])


def stamp_free_view(data: bytes | memoryview) -> memoryview:
    """:func:`stamp_free_key` without copying (an image's: compared only now and then)."""
    return memoryview(data)[_STAMP_END:]


def header_stamp_ns(data: bytes | memoryview, serialization: str) -> int | None:
    """Header stamp of a serialized message whose first field is a std_msgs/Header, read
    without deserializing: little-endian CDR or ROS1 (None for big-endian CDR).

    >>> from replay.wire import serialize
    >>> from replay.messages import PointStamped
    >>> header_stamp_ns(serialize(PointStamped(1_500_000_007, "f", np.zeros(3))), "cdr")
    1500000007
    """
    if serialization == "cdr" and bytes(data[:2]) != b"\x00\x01":  # CDR_LE encapsulation
        return None
    sec, nanosec = struct.unpack_from("<iI", data, 4)
    return int(sec) * 1_000_000_000 + int(nanosec)
