"""Camera poses from the scenario record and from a right camera's projection matrix."""

from __future__ import annotations

import numpy as np
import pytest

from replay.camera import CameraModel
from replay.messages import CameraInfo
from replay.records import Scenario, ScenarioCamera
from rerun_export.rig import baseline_m, rig_poses, stereo_partner

MODEL = CameraModel.ideal(640, 480, 0.6)


def info(ns_frame: str, baseline: float = 0.0) -> CameraInfo:
    return MODEL.camera_info(stamp_ns=0, frame_id=ns_frame, baseline_tx=-MODEL.fx * baseline)


def test_baseline_from_projection() -> None:
    assert baseline_m(info("r", 0.09)) == pytest.approx(0.09, abs=1e-12)
    assert baseline_m(info("l")) is None


def test_partner_names() -> None:
    spaces = ["/a/left", "/a/right", "/b/right"]
    assert stereo_partner("/a/right", spaces) == "/a/left"
    assert stereo_partner("/b/right", spaces) is None
    assert stereo_partner("/a/left", spaces) is None


def test_baseline_rig_puts_the_right_camera_along_the_left_x() -> None:
    rig = rig_poses(["/s/left", "/s/right"], frame_ids={}, scenario=None,
                    infos={"/s/left": info("l"), "/s/right": info("r", 0.02)})
    assert not rig.world_is_scenario
    np.testing.assert_array_equal(rig.world_from_camera["/s/left"], np.eye(4))
    expected = np.eye(4)
    expected[0, 3] = 0.02
    np.testing.assert_allclose(rig.world_from_camera["/s/right"], expected, atol=1e-15)
    assert rig.source == {"/s/left": "baseline", "/s/right": "baseline"}


def scenario(namespace: str, frame_id: str, world_from_camera: np.ndarray) -> Scenario:
    camera = ScenarioCamera(
        name="c", namespace=namespace, frame_id=frame_id, width=640, height=480, k=MODEL.k,
        distortion_model="plumb_bob", d=np.zeros(5), world_from_camera=world_from_camera,
        render_size=(640, 480), supersample=1)
    return Scenario(scenario="s", source="test", seed=0, camlog_version="", mujoco_version="",
                    renderer="", spec={}, cameras=[camera], targets=[])


def test_scenario_poses_match_by_namespace_then_frame() -> None:
    pose = np.eye(4)
    pose[:3, 3] = [1, 2, 3]
    rig = rig_poses(["/stereo_sync/left", "/other"],
                    scenario=scenario("/unsynced/left", "left_optical", pose), infos={},
                    frame_ids={"/stereo_sync/left": "left_optical", "/other": "x"})
    assert rig.world_is_scenario
    np.testing.assert_array_equal(rig.world_from_camera["/stereo_sync/left"], pose)
    assert "/other" not in rig.world_from_camera


def test_a_bad_scenario_pose_is_ignored() -> None:
    bad = scenario("/c", "c", np.array([[1.0, 2], [3, 4]]))
    rig = rig_poses(["/c"], scenario=bad, infos={}, frame_ids={})
    assert rig.world_from_camera == {}
