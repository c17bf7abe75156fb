"""Poses aimed at the image: boards in all four corners (camera_calibration's X and Y
coverage >= 90 %), partial ChArUco views, stereo poses fully visible in at least one camera,
anchors a stereo pair cannot both see replaced by others."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from processors.calibration.board import Board
from processors.calibration.selection import coverage, view_parameters
from recorder import motion
from recorder.cameras import CameraSpec
from recorder.coverage import ANCHORS, anchor_order, image_pose, view_angles
from recorder.errors import ScenarioError
from recorder.motion import Trajectory, plan_trajectory, visible_fraction
from recorder.record import MOTION_STREAM, rng_for
from recorder.scenario import ScenarioSpec, builtin_dir, load_scenario, parse_scenario
from recorder.targets import feature_points_in_target, outline_in_target
from replay.geometry import invert
from replay.messages import F64


def planned(name: str) -> tuple[ScenarioSpec, Trajectory]:
    scenario = load_scenario(name)
    (target,) = scenario.targets
    trajectory = plan_trajectory(target, scenario.cameras, scenario.frame_count / 30,
                                 rng_for(scenario, MOTION_STREAM, 0))  # as recorded
    assert isinstance(trajectory, Trajectory)
    return scenario, trajectory


def projected(camera: CameraSpec, world_from_target: F64, points: F64) -> F64 | None:
    camera_from_target = invert(camera.world_from_camera) @ world_from_target
    in_camera = points @ camera_from_target[:3, :3].T + camera_from_target[:3, 3]
    return None if (in_camera[:, 2] <= 0).any() else camera.model.project(in_camera)


def ros_coverage(scenario: ScenarioSpec, trajectory: Trajectory, camera: CameraSpec) -> F64:
    """camera_calibration's X, Y progress over the fully visible board views."""
    (target,) = scenario.targets
    board = Board(*target.inner_corners, target.square_m)
    points = feature_points_in_target(target)
    size = (camera.model.width, camera.model.height)
    params, corners = [], []
    for pose in trajectory.world_from_target:
        if visible_fraction(pose, outline_in_target(target), (camera,)) < 1.0:
            continue
        uv = projected(camera, pose, points)
        assert uv is not None
        params.append(view_parameters(uv, board, size))
        corners.append(uv)
    result = coverage(np.array(params), corners, size)
    return np.array([result.ranges["X"][2], result.ranges["Y"][2]])


def test_anchors_are_visited_in_turn() -> None:
    order = anchor_order(27, np.random.default_rng(3))
    for start in range(0, 27, 9):
        assert sorted(order[start:start + 9]) == list(range(len(ANCHORS)))


def test_mono_poses_reach_every_image_corner() -> None:
    scenario, trajectory = planned("mono_heldout")
    (camera,) = scenario.cameras
    (target,) = scenario.targets
    assert (ros_coverage(scenario, trajectory, camera) >= 0.9).all()
    w, h = camera.model.width, camera.model.height
    outline = outline_in_target(target)
    reached = set()
    for pose in trajectory.world_from_target:
        uv = projected(camera, pose, outline)
        assert uv is not None
        low, high = uv.min(axis=0), uv.max(axis=0)
        # the board's bounding box touches both borders of a corner
        left, top = low[0] < 30, low[1] < 30
        right, bottom = high[0] > w - 31, high[1] > h - 31
        reached |= {name for name, hit in (("top left", left and top),
                                           ("top right", right and top),
                                           ("bottom left", left and bottom),
                                           ("bottom right", right and bottom)) if hit}
    assert len(reached) == 4


def test_today_world_poses_cover_less_of_the_width() -> None:
    """The reason for aiming at the image: poses around a point in the world."""
    scenario, trajectory = planned("mono_checkerboard")
    heldout, aimed = planned("mono_heldout")
    assert ros_coverage(scenario, trajectory, scenario.cameras[0])[0] < ros_coverage(
        heldout, aimed, heldout.cameras[0])[0]


def test_stereo_poses_are_fully_visible_in_at_least_one_camera() -> None:
    scenario, trajectory = planned("stereo_heldout")
    left, right = scenario.cameras
    left_from_right = invert(left.world_from_camera) @ right.world_from_camera
    yaw_deg = math.degrees(math.atan2(left_from_right[0, 2], left_from_right[2, 2]))
    assert yaw_deg == pytest.approx(-1.2, abs=1e-4)
    (target,) = scenario.targets
    outline = outline_in_target(target)
    seen = np.array([[visible_fraction(p, outline, (c,)) for c in (left, right)]
                     for p in trajectory.world_from_target])
    full_somewhere = seen.max(axis=1) == 1.0
    partial = ~full_somewhere
    assert full_somewhere.mean() > 0.85
    assert (seen.max(axis=1)[partial] >= 0.25).all()
    assert (seen.min(axis=1) < 1.0).any()  # some views help one camera only
    for camera in (left, right):
        assert (ros_coverage(scenario, trajectory, camera) >= 0.9).all()


def test_charuco_views_are_partial_as_asked() -> None:
    scenario, trajectory = planned("mono_charuco")
    (target,) = scenario.targets
    p = target.motion.partial_view_probability
    outline = outline_in_target(target)
    seen = np.array([visible_fraction(pose, outline, scenario.cameras)
                     for pose in trajectory.world_from_target])
    partial = seen < 1.0
    assert (seen[partial] >= 0.25).all()
    n = len(seen)
    assert abs(partial.mean() - p) < 4 * math.sqrt(p * (1 - p) / n)


def test_fisheye_poses_stay_within_the_view_angle() -> None:
    scenario, trajectory = planned("mono_fisheye")
    (camera,) = scenario.cameras
    (target,) = scenario.targets
    limit = target.motion.max_view_angle_rad
    angles = [view_angles(camera, pose, outline_in_target(target)).max()
              for pose in trajectory.world_from_target]
    assert max(angles) <= limit and max(angles) > limit - 0.15  # out to the limit


def test_image_aim_plans_held_poses_only() -> None:
    raw = tomllib.loads((builtin_dir() / "mono_moving_blur.toml").read_text())
    raw["targets"][0]["motion"]["aim"] = "image"
    with pytest.raises(ScenarioError, match="aim"):
        parse_scenario(raw, "test")


def stereo_heldout_visible_in(visible_in: str, **motion_changes: object) -> ScenarioSpec:
    raw = tomllib.loads((builtin_dir() / "stereo_heldout.toml").read_text())
    raw["targets"][0]["motion"].update(visible_in=visible_in, **motion_changes)
    return parse_scenario(raw, "test")


def test_anchors_both_stereo_cameras_cannot_see_move_to_others(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the anchors both cameras see meet within a few tries: 300 are plenty
    monkeypatch.setattr(motion, "MAX_TRIES", 300)
    scenario = stereo_heldout_visible_in("all")
    left, right = scenario.cameras
    (target,) = scenario.targets
    outline = outline_in_target(target)
    # a board pushed to the left image's left border is out of the right camera's view
    rng = np.random.default_rng(0)
    left_border = ANCHORS.index((0.0, None))
    for _ in range(300):
        pose = image_pose(target, left, left_border, partial=False, rng=rng)
        assert pose is None or visible_fraction(pose, outline, (left, right)) < 1.0
    trajectory = plan_trajectory(target, scenario.cameras, 60.0,
                                 rng_for(scenario, MOTION_STREAM, 0))
    assert isinstance(trajectory, Trajectory)
    seen = np.array([visible_fraction(p, outline, (left, right))
                     for p in trajectory.world_from_target])
    assert len(seen) == 121
    assert (seen[seen < 1.0] >= 0.25).all()
    assert (seen == 1.0).mean() > 0.85


def test_an_image_no_anchor_can_meet_is_one_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(motion, "MAX_TRIES", 50)
    # 2 cm from the lens the 8 x 7 cm board is always wider than the image
    scenario = stereo_heldout_visible_in("any", distance_m=[0.02, 0.02],
                                         partial_view_probability=0.0)
    with pytest.raises(ScenarioError, match=(
            r"^target 'checkerboard': no fully visible pose aimed at camera 'left''s image "
            r"found at any of the 9 anchors in 50 tries each; change distance_m")):
        plan_trajectory(scenario.targets[0], scenario.cameras, 1.0, np.random.default_rng(0))
