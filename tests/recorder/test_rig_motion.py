"""A moving rig: every camera carried along one smooth path over a textured scene, the truth
following it."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from recorder.errors import ScenarioError
from recorder.rig_motion import CameraPoses, RigMotionSpec, plan_rig_path
from recorder.scenario import load_scenario
from recorder.targets import texture_image
from replay.geometry import invert

from .logs import Log, transform

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"


@pytest.fixture(scope="module")
def moving(recording: Callable[..., Log]) -> Log:
    """stereo_moving_rig, 12 frames at 160x120."""
    return recording("stereo_moving_rig", frames=12, width=160, height=120)


def test_the_rig_moves_as_one() -> None:
    scenario = load_scenario("stereo_moving_rig")
    assert scenario.rig_motion is not None
    path = plan_rig_path(scenario.rig_motion, 4.0, np.random.default_rng(0))
    poses = CameraPoses(scenario.cameras, path=path)
    rest = [c.world_from_camera for c in scenario.cameras]
    moved = []
    for t in np.linspace(0.0, 4.0, 9):
        left, right = (poses.world_from_camera(i, float(t)) for i in range(2))
        np.testing.assert_allclose(invert(right) @ left, invert(rest[1]) @ rest[0], atol=1e-12)
        moved.append(np.linalg.norm(left[:3, 3] - rest[0][:3, 3]))
    assert 0.005 < max(moved) < np.linalg.norm(scenario.rig_motion.translation_m) + 1e-9
    assert not CameraPoses(scenario.cameras).moving


def test_the_path_is_smooth_and_within_its_ranges() -> None:
    spec = RigMotionSpec(0.5, np.array([0.03, 0.02, 0.01]), np.array([0.1, 0.1, 0.05]))
    path = plan_rig_path(spec, 3.0, np.random.default_rng(1))
    assert np.all(np.abs(path.waypoints) <= np.concatenate([spec.translation_m,
                                                            spec.rotation_rad]))
    step = 1e-4
    a, b = path.rest_from_moved(1.2 - step), path.rest_from_moved(1.2 + step)
    assert np.linalg.norm(b[:3, 3] - a[:3, 3]) < 0.01 * step / 1e-4  # under 1 m/s


def test_the_truth_follows_the_moving_cameras(moving: Log) -> None:
    floors = [transform(p) for p in moving.truths(LEFT, "floor")]
    rights = [transform(p) for p in moving.truths(RIGHT, "floor")]
    assert len(floors) == 12
    # the floor stands still: the camera moves relative to it
    assert np.linalg.norm(floors[0][:3, 3] - floors[-1][:3, 3]) > 1e-3
    left_from_right = [f @ invert(r) for f, r in zip(floors, rights, strict=True)]
    for pose in left_from_right:
        np.testing.assert_allclose(pose, left_from_right[0], atol=1e-9)
    np.testing.assert_allclose(left_from_right[0][:3, 3], [0.06, 0.0, 0.0], atol=1e-9)


def test_the_scene_is_textured_and_the_images_move(moving: Log) -> None:
    first, last = moving.images(LEFT)[0].pixels, moving.images(LEFT)[-1].pixels
    assert first.std() > 40  # grey blobs, black to white
    assert np.abs(first.astype(int) - last.astype(int)).mean() > 10
    texture = texture_image(load_scenario("stereo_moving_rig").targets[0])
    assert texture.dtype == np.uint8 and texture.std() > 60
    np.testing.assert_array_equal(texture,
                                  texture_image(load_scenario("stereo_moving_rig").targets[0]))


@pytest.mark.parametrize(("table", "match"), [
    ({"translation_m": [-0.1, 0, 0]}, "ranges must be >= 0"),
    ({"rotation_rad": [0.9, 0, 0]}, r"within \[0, 0.5\]"),
    ({"kind": "jerky"}, "must be one of smooth"),
    ({"speed": 1}, "speed: unknown key"),
])
def test_bad_rig_motion_is_one_error(table: dict[str, object], match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        load_scenario("stereo_checkerboard", {"rig_motion": table})


def test_a_textured_box_needs_grains_it_can_hold() -> None:
    with pytest.raises(ScenarioError, match="grains across the box"):
        load_scenario("stereo_moving_rig", {"targets": [{
            "name": "wall", "kind": "textured", "size_m": [2.0, 2.0, 0.01],
            "grain_m": 0.001}]})
