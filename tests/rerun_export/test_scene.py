"""Planning the entity layout from a survey (no log needed)."""

from __future__ import annotations

import numpy as np
import pytest

from replay.camera import CameraModel
from replay.display import Display
from replay.formats.base import TopicInfo
from replay.messages import CameraInfo
from replay.records import ProcessedOutput
from rerun_export.scene import plan_scene
from rerun_export.survey import Survey
from rerun_export.topics import classify


def survey_of(topics: dict[str, tuple[str, int]], frame_ids: dict[str, str],
              outputs: dict[str, ProcessedOutput] | None = None) -> Survey:
    found = Survey()
    for name, (msgtype, count) in topics.items():
        found.topics[name] = TopicInfo(name, msgtype, count, "cdr")
        found.routes[name] = classify(name, msgtype, outputs)
        found.owner[name] = 0
    found.frame_ids.update(frame_ids)
    return found


IMAGE, COMPRESSED = "sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"
INFO, POINT = "sensor_msgs/msg/CameraInfo", "geometry_msgs/msg/PointStamped"


def test_raw_images_win_over_their_compressed_copy() -> None:
    plan = plan_scene(survey_of({"/c/image_raw/compressed": (COMPRESSED, 5),
                                 "/c/image_raw": (IMAGE, 5), "/c/camera_info": (INFO, 5)},
                                {"/c/image_raw": "c_frame"}))
    (cam,) = plan.cameras.values()
    assert cam.image_topic == "/c/image_raw" and cam.info_topic == "/c/camera_info"
    assert plan.skipped == {"/c/image_raw/compressed": "same camera as /c/image_raw"}
    assert cam.viewable and cam.entity == "world/c" and plan.frames == {"c_frame": ["/c"]}


def test_outputs_find_their_camera_by_frame_or_get_one() -> None:
    found = survey_of({"/a/image_raw": (IMAGE, 5), "/b/image_raw": (IMAGE, 5),
                       "/image_converter/red_centroid": (POINT, 5),
                       "/image_converter/edges": (IMAGE, 5)},
                      {"/a/image_raw": "shared", "/b/image_raw": "shared",
                       "/image_converter/red_centroid": "shared",
                       "/image_converter/edges": "lonely"})
    plan = plan_scene(found)
    assert plan.frames["shared"] == ["/a", "/b"]
    assert plan.frames["lonely"] == ["/frame/lonely"]
    assert plan.cameras["/frame/lonely"].viewable
    assert plan.cameras["/frame/lonely"].entity == "world/frame/lonely"


def test_recorded_outputs_plan_their_camera_series_and_views() -> None:
    declared = [("/b/edges", IMAGE, Display.EDGES, "edges", "Canny edges"),
                ("/b/n", POINT, Display.SCALAR, "blob_count", "blob count"),
                ("/b/r/n", POINT, Display.SCALAR, "blob_count", "blob count"),
                ("/b/small", IMAGE, Display.IMAGE, "resize/small", "resized")]
    outputs = {topic: ProcessedOutput(topic, "/b/image_raw", "p", topic.rpartition("/")[2],
                                      msgtype, display.value, entity, label)
               for topic, msgtype, display, entity, label in declared}
    found = survey_of({topic: (msgtype, 5) for topic, msgtype, *_ in declared}
                      | {"/c/image_raw": (IMAGE, 5)}, {"/c/image_raw": "c"}, outputs)
    plan = plan_scene(found)
    # the source camera's images are not in these logs: its outputs still get its view
    assert list(plan.cameras) == ["/b", "/c"] and plan.cameras["/b"].viewable
    assert [(s.origin, s.title) for s in plan.series] == [("metrics/blob_count", "blob count")]
    assert plan.images == ["processed/b/small"] and plan.rectified == []


def test_baseline_rig_and_plane_distance() -> None:
    model = CameraModel.ideal(64, 48, 1.0)
    found = survey_of({f"/s/{side}/{kind}": (t, 3) for side in ("left", "right")
                       for kind, t in (("image_raw", IMAGE), ("camera_info", INFO))}, {})
    found.camera_infos["/s/left/camera_info"] = model.camera_info(stamp_ns=0, frame_id="l")
    found.camera_infos["/s/right/camera_info"] = model.camera_info(
        stamp_ns=0, frame_id="r", baseline_tx=-model.fx * 0.1)
    plan = plan_scene(found)
    assert plan.rig.source == {"/s/left": "baseline", "/s/right": "baseline"}
    assert plan.image_plane_distance_m == pytest.approx(0.25)  # 2.5 baselines


def test_a_distorted_camera_gets_pinhole_views_and_a_raw_space() -> None:
    """The calibrated camera_info draws the camera; a lens that is not a pinhole sends the
    raw image to raw/NS and gets views; a pinhole camera, or none wanted, stays as it was."""
    found = survey_of({"/c/image_raw": (IMAGE, 5), "/c/camera_info": (INFO, 5),
                       "/c/calibrated/camera_info": (INFO, 5), "/p/image_raw": (IMAGE, 5),
                       "/p/camera_info": (INFO, 5)}, {"/c/image_raw": "c", "/p/image_raw": "p"})
    ideal = CameraModel.ideal(64, 48, 1.0).camera_info(stamp_ns=0, frame_id="c")
    distorted = CameraInfo(0, "c", 64, 48, "plumb_bob", np.array([-0.2, 0.05, 0, 0, 0]),
                           ideal.k)
    found.camera_infos.update({"/c/camera_info": ideal, "/c/calibrated/camera_info": distorted,
                               "/p/camera_info": ideal})
    plan = plan_scene(found)
    lens, pinhole = plan.cameras["/c"], plan.cameras["/p"]
    assert lens.info_topics == ["/c/calibrated/camera_info", "/c/camera_info"]
    assert [v.name for v in lens.views] == ["undistorted"] and lens.info is distorted
    assert (lens.entity, lens.raw_entity) == ("world/c", "raw/c")
    assert pinhole.views == [] and pinhole.raw_entity == "world/p"
    assert plan.undistorted == 0.5  # half the raw images by default
    off = plan_scene(found, undistorted_scale=None)
    assert off.cameras["/c"].views == [] and off.cameras["/c"].raw_entity == "world/c"
