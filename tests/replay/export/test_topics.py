"""Every topic camlog writes is routed to the view it belongs to."""

from __future__ import annotations

import pytest

from replay.export.topics import COMPRESSED, Kind, Route, classify

IMAGE, INFO = "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo"
POINT, POSE, STRING = ("geometry_msgs/msg/PointStamped", "geometry_msgs/msg/PoseStamped",
                       "std_msgs/msg/String")


@pytest.mark.parametrize(("topic", "msgtype", "route"), [
    ("/stereo_camera/left/image_raw", IMAGE, Route(Kind.IMAGE, "/stereo_camera/left")),
    ("/cam/image_raw/compressed", COMPRESSED, Route(Kind.IMAGE, "/cam")),
    ("/cam/camera_info", INFO, Route(Kind.CAMERA_INFO, "/cam")),
    ("/cam/calibrated/camera_info", INFO, Route(Kind.CALIBRATED_INFO, "/cam")),
    ("/cam/image_rect", IMAGE, Route(Kind.RECTIFIED, "/cam")),
    ("/cam/calibration/detections", IMAGE, Route(Kind.DETECTIONS, "/cam")),
    ("/cam/calibration/residuals", STRING, Route(Kind.RESIDUALS, "/cam")),
    ("/cam/calibration/view_error", POINT, Route(Kind.VIEW_ERROR, "/cam")),
    ("/image_converter/output_video", IMAGE, Route(Kind.RED_MASK, by_frame=True)),
    ("/image_converter/output_video/compressed", COMPRESSED,
     Route(Kind.RED_MASK, by_frame=True)),
    ("/image_converter/red_centroid", POINT, Route(Kind.RED_CENTROID, by_frame=True)),
    ("/image_converter/red_count", POINT, Route(Kind.RED_COUNT, by_frame=True)),
    ("/image_converter/edges", IMAGE, Route(Kind.EDGES, by_frame=True)),
    ("/image_converter/image_rect", IMAGE, Route(Kind.RECTIFIED, by_frame=True)),
    ("/cam/ground_truth/checkerboard", POSE,
     Route(Kind.GROUND_TRUTH, "/cam", detail="checkerboard")),
    ("/stereo_sync/offset_s", POINT, Route(Kind.STEREO_OFFSET, "/stereo_sync")),
    ("/stereo_sync/stats", STRING, Route(Kind.TEXT, "/stereo_sync/stats")),
    ("/camera/fisheye1/image_raw", IMAGE, Route(Kind.IMAGE, "/camera/fisheye1")),
    ("/some/picture", IMAGE, Route(Kind.IMAGE, "/some/picture")),
    ("/some/point", POINT, Route(Kind.POINT_SERIES, "/some/point")),
    ("/camera/imu", "sensor_msgs/msg/Imu", Route(Kind.SKIPPED)),
    ("/pose", POSE, Route(Kind.SKIPPED)),
])
def test_classify(topic: str, msgtype: str, route: Route) -> None:
    assert classify(topic, msgtype) == route
