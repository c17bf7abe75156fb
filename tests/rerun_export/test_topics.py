"""Every topic camlog writes is routed to the view it belongs to."""

from __future__ import annotations

import pytest

from replay.display import Display
from replay.records import ProcessedOutput
from rerun_export.topics import Kind, Route, classify

IMAGE, INFO = "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
POINT, POSE, STRING = ("geometry_msgs/msg/PointStamped", "geometry_msgs/msg/PoseStamped",
                       "std_msgs/msg/String")


MASK = Route(Kind.MASK, by_frame=True, entity="red_pixels/mask", label="red pixels")


@pytest.mark.parametrize(("topic", "msgtype", "route"), [
    ("/stereo_camera/left/image_raw", IMAGE, Route(Kind.IMAGE, "/stereo_camera/left")),
    ("/cam/image_raw/compressed", COMPRESSED, Route(Kind.IMAGE, "/cam")),
    ("/cam/camera_info", INFO, Route(Kind.CAMERA_INFO, "/cam")),
    ("/cam/calibrated/camera_info", INFO, Route(Kind.CALIBRATED_INFO, "/cam")),
    ("/cam/image_rect", IMAGE, Route(Kind.RECTIFIED, "/cam")),
    ("/cam/calibration/detections", IMAGE, Route(Kind.DETECTIONS, "/cam")),
    ("/cam/calibration/residuals", STRING, Route(Kind.RESIDUALS, "/cam")),
    ("/cam/calibration/view_error", POINT, Route(Kind.VIEW_ERROR, "/cam")),
    ("/image_converter/output_video", IMAGE, MASK),
    ("/image_converter/output_video/compressed", COMPRESSED, MASK),
    ("/image_converter/red_centroid", POINT, Route(Kind.POINT_2D, by_frame=True,
                                                   entity="red_pixels/centroid",
                                                   label="red centroid")),
    ("/image_converter/red_count", POINT, Route(Kind.SCALAR, by_frame=True,
                                                entity="red_pixel_count",
                                                label="red pixel count")),
    ("/image_converter/edges", IMAGE, Route(Kind.EDGES, by_frame=True, entity="edges",
                                            label="Canny edges")),
    ("/image_converter/image_rect", IMAGE, Route(Kind.RECTIFIED, by_frame=True,
                                                 label="rectified")),
    # without a record, a processor's output under a camera is just another image
    ("/cam/edges", IMAGE, Route(Kind.IMAGE, "/cam/edges")),
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


def output(topic: str, display: Display, source: str = "/cam/image_raw/compressed",
           msgtype: str = IMAGE) -> ProcessedOutput:
    return ProcessedOutput(topic=topic, source=source, processor="p", output="o",
                           msgtype=msgtype, display=display.value, entity="p/o", label="thing")


@pytest.mark.parametrize(("recorded", "route"), [
    (output("/cam/edges", Display.EDGES), Route(Kind.EDGES, "/cam", entity="p/o",
                                                label="thing")),
    (output("/out/mask/compressed", Display.MASK, msgtype=COMPRESSED),
     Route(Kind.MASK, "/cam", entity="p/o", label="thing")),
    (output("/cam/small", Display.IMAGE), Route(Kind.PROCESSED_IMAGE, "/cam", entity="p/o",
                                                label="thing")),
    (output("/x/n", Display.SCALAR, "/a/b/image_raw", POINT),
     Route(Kind.SCALAR, "/a/b", entity="p/o", label="thing")),
    (output("/x/xyz", Display.POINT_SERIES, msgtype=POINT),
     Route(Kind.POINT_SERIES, "/x/xyz", entity="p/o", label="thing")),
    # a record names the chapter's topics too: it wins over the name
    (output("/image_converter/edges", Display.IMAGE, "/right/image_raw"),
     Route(Kind.PROCESSED_IMAGE, "/right", entity="p/o", label="thing")),
])
def test_recorded_outputs_are_routed_by_their_record(recorded: ProcessedOutput,
                                                     route: Route) -> None:
    assert classify(recorded.topic, recorded.msgtype, {recorded.topic: recorded}) == route
    assert classify(recorded.topic, recorded.msgtype, {}) != route


def test_a_display_this_camlog_does_not_know_falls_back_to_the_name() -> None:
    recorded = ProcessedOutput(topic="/image_converter/edges", source="/cam/image_raw",
                               processor="p", output="o", msgtype=IMAGE, display="hologram",
                               entity="p/o", label="thing")
    assert classify(recorded.topic, IMAGE, {recorded.topic: recorded}) == \
        classify(recorded.topic, IMAGE)
