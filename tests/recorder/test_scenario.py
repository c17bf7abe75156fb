"""Scenario specs: built-ins, overrides, resolved cameras and targets, and spec errors."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from recorder.errors import ScenarioError
from recorder.scenario import apply_overrides, builtin_names, load_scenario
from tests.conftest import REPO_ROOT

SCENARIO_DIR = REPO_ROOT / "datasets" / "scenarios"
BUILTINS = sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def test_builtins_are_the_shipped_specs() -> None:
    assert BUILTINS == ["mono_charuco", "mono_checkerboard", "mono_circles", "mono_fisheye",
                        "mono_heldout", "mono_moving_blur", "red_block", "stereo_checkerboard",
                        "stereo_heldout", "stereo_moving_board", "stereo_moving_rig",
                        "stereo_unsynced"]
    assert builtin_names() == BUILTINS


#: the scenarios of the chapter's camera; the others are calibration cases with their own lens
CHAPTER = ["mono_checkerboard", "red_block", "stereo_checkerboard", "stereo_unsynced"]


@pytest.mark.parametrize("name", CHAPTER)
def test_builtin_cameras_are_the_chapter_camera(name: str) -> None:
    s = load_scenario(name)
    raw = tomllib.loads((SCENARIO_DIR / f"{name}.toml").read_text())
    assert s.name == name == raw["name"]
    assert s.spec == raw
    assert s.frame_count == round(raw["duration_s"] * raw["rate_hz"])
    fx = 320 / math.tan(0.3)
    for camera in s.cameras:
        np.testing.assert_allclose(camera.model.k, [[fx, 0, 319.5], [0, fx, 239.5], [0, 0, 1]])
        assert camera.model.is_ideal and camera.supersample == 2
        assert camera.encoding == "rgb8"
        # optical frame looking straight down from 0.5 m (the right camera 2 cm to its side)
        np.testing.assert_allclose(camera.world_from_camera[:3, 2], [0, 0, -1], atol=1e-12)
        assert camera.world_from_camera[2, 3] == pytest.approx(0.5)


def test_default_scenario_is_mono_checkerboard() -> None:
    assert load_scenario().name == load_scenario(None).name == "mono_checkerboard"


@pytest.mark.parametrize("name", ["stereo_checkerboard", "red_block", "stereo_unsynced"])
def test_right_camera_is_the_left_one_shifted_by_the_baseline(name: str) -> None:
    left, right = load_scenario(name).cameras
    left_from_right = np.linalg.inv(left.world_from_camera) @ right.world_from_camera
    np.testing.assert_allclose(left_from_right[:3, :3], np.eye(3), atol=1e-12)
    np.testing.assert_allclose(left_from_right[:3, 3], [0.02, 0, 0], atol=1e-12)
    assert left.baseline_tx == 0.0
    assert right.baseline_tx == pytest.approx(-left.model.fx * 0.02)


def test_red_block_sits_01_m_in_front_of_the_left_camera() -> None:
    s = load_scenario("red_block")
    (target,) = s.targets
    left = s.cameras[0]
    target_in_left = np.linalg.inv(left.world_from_camera) @ target.motion.world_from_target
    np.testing.assert_allclose(target_in_left[:3, 3], [0, 0, 0.1], atol=1e-12)
    np.testing.assert_allclose(target.size_m, [0.02, 0.02, 0.01])


def test_overrides_reach_every_camera() -> None:
    s = load_scenario("stereo_checkerboard", {
        "seed": 5, "frames": 12, "width": 320, "height": 240, "hfov_rad": 0.8,
        "noise_std": 2.0, "encoding": "mono8", "distortion": [-0.1, 0.0, 0.0, 0.0, 0.0],
        "duration_s": None,
    })
    assert (s.seed, s.frames, s.frame_count) == (5, 12, 12)
    assert "duration_s" not in s.spec  # frames replaces the spec's duration
    fx = 160 / math.tan(0.4)
    for camera in s.cameras:
        np.testing.assert_allclose(camera.model.k, [[fx, 0, 159.5], [0, fx, 119.5], [0, 0, 1]])
        np.testing.assert_array_equal(camera.model.d, [-0.1, 0, 0, 0, 0])
        assert (camera.noise_std, camera.encoding) == (2.0, "mono8")
        assert camera.supersample == 2  # distorted cameras are supersampled by default
    assert s.cameras[1].baseline_tx == pytest.approx(-fx * 0.02)


def test_intrinsics_and_distortion_model_overrides() -> None:
    s = load_scenario("mono_checkerboard", {
        "intrinsics": [500.0, 510.0, 300.0, 250.0], "distortion_model": "rational_polynomial",
        "distortion": [0.1] * 8, "supersample": 3,
    })
    (camera,) = s.cameras
    np.testing.assert_array_equal(camera.model.k, [[500, 0, 300], [0, 510, 250], [0, 0, 1]])
    assert camera.model.distortion_model == "rational_polynomial"
    np.testing.assert_array_equal(camera.model.d, [0.1] * 8)
    assert camera.supersample == 3


def test_duration_override_replaces_frames() -> None:
    raw = {"name": "x", "frames": 10, "cameras": []}
    out = apply_overrides(raw, {"duration_s": 2.0})
    assert out == {"name": "x", "duration_s": 2.0, "cameras": []}
    assert raw == {"name": "x", "frames": 10, "cameras": []}  # not modified
    s = load_scenario("mono_checkerboard", {"duration_s": 2.0})
    assert s.frame_count == 60


# --- spec errors ----------------------------------------------------------------------------

MINIMAL = """
name = "tiny"
[[cameras]]
name = "cam"
position_m = [0.0, 0.0, 0.5]
forward = [0.0, 0.0, -1.0]
right = [0.0, 1.0, 0.0]
"""


def write_spec(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_minimal_spec_has_the_documented_defaults(tmp_path: Path) -> None:
    s = load_scenario(str(write_spec(tmp_path, MINIMAL)))
    (camera,) = s.cameras
    assert (s.seed, s.rate_hz, s.frame_count, s.targets) == (0, 30.0, 300, ())
    assert (camera.model.width, camera.model.height) == (640, 480)
    assert camera.model.fx == pytest.approx(320 / math.tan(0.3))
    assert camera.namespace == "/cam" and camera.frame_id == "cam_optical_frame"


def test_unknown_scenario_lists_the_builtins() -> None:
    with pytest.raises(ScenarioError) as info:
        load_scenario("no_such_scenario")
    message = str(info.value)
    assert "no_such_scenario" in message
    assert all(name in message for name in BUILTINS)


def test_missing_spec_file(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="does not exist"):
        load_scenario(str(tmp_path / "missing.toml"))


def test_invalid_toml_names_the_file(tmp_path: Path) -> None:
    path = write_spec(tmp_path, "name = \n")
    with pytest.raises(ScenarioError, match=r"spec\.toml: not valid TOML"):
        load_scenario(str(path))


SECOND_CAMERA = (
    '[[cameras]]\nname = "{name}"\nrelative_to = "{parent}"\ntranslation_m = [0, 0, 0]\n'
)
BOARD = '[[targets]]\nname = "board"\nkind = "checkerboard"\n'

#: case -> (spec text, what the message must name)
BAD_SPECS: dict[str, tuple[str, str]] = {
    "width not a number": (MINIMAL + 'width = "abc"\n', "cameras[0].width"),
    "unknown camera key": (MINIMAL + "colour = 3\n", "cameras[0].colour: unknown key"),
    "negative noise": (MINIMAL + "noise_std = -1.0\n", "cameras[0].noise_std"),
    "supersample 5": (MINIMAL + "supersample = 5\n", "cameras[0].supersample"),
    "drop probability 1": (MINIMAL + "drop_probability = 1.0\n", "cameras[0].drop_probability"),
    "bad encoding": (MINIMAL + 'encoding = "yuv422"\n', "cameras[0].encoding"),
    "too many coefficients": (MINIMAL + "distortion = [0, 0, 0, 0, 0, 0]\n",
                              "cameras[0].distortion"),
    "parallel axes": (MINIMAL.replace("right = [0.0, 1.0, 0.0]", "right = [0.0, 0.0, 2.0]"),
                      "cameras[0].forward"),
    "unknown relative_to": (MINIMAL + SECOND_CAMERA.format(name="b", parent="nope"),
                            "cameras[1].relative_to"),
    "duplicate camera": (MINIMAL + SECOND_CAMERA.format(name="cam", parent="cam"),
                         "names must be unique"),
    "unknown top-level key": ("speed = 3\n" + MINIMAL, "speed: unknown key"),
    "bad inner corners": (MINIMAL + BOARD + "inner_corners = [1, 6]\n",
                          "targets[0].inner_corners"),
    "reversed z range": (MINIMAL + BOARD + '[targets.motion]\nkind = "random_hold"\n'
                         "z_range_m = [0.3, 0.1]\n", "targets[0].motion.z_range_m"),
}


@pytest.mark.parametrize("case", sorted(BAD_SPECS))
def test_bad_values_name_file_and_key(tmp_path: Path, case: str) -> None:
    text, needle = BAD_SPECS[case]
    path = write_spec(tmp_path, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(str(path))
    message = str(info.value)
    assert message.startswith(str(path))
    assert needle in message
    assert "\n" not in message


@pytest.mark.parametrize(("overrides", "key"), [
    ({"frames": 0}, "frames"),
    ({"seed": -1}, "seed"),
    ({"hfov_rad": 0.0}, "hfov_rad"),
    ({"intrinsics": [-1.0, 500.0, 320.0, 240.0]}, "fx"),
])
def test_bad_overrides_are_spec_errors(overrides: dict[str, Any], key: str) -> None:
    with pytest.raises(ScenarioError, match=key):
        load_scenario("mono_checkerboard", overrides)


def test_mono_fisheye_sees_more_than_150_degrees_across() -> None:
    (camera,) = load_scenario("mono_fisheye").cameras
    model = camera.model
    assert model.is_fisheye and model.distortion_model == "equidistant"
    assert model.d.size == 4 and np.any(model.d)
    left_right = model.pixel_rays(np.array([[0.0, model.cy], [model.width - 1.0, model.cy]]))
    assert np.degrees(np.arccos(left_right[:, 2])).sum() >= 150
    np.testing.assert_allclose(camera.world_from_camera[:3, 2], [0, 0, -1], atol=1e-12)


def test_fisheye_field_of_view_may_pass_180_degrees() -> None:
    """For a fisheye ``hfov_rad`` sets fx = (W / 2) / (hfov / 2); a pinhole stays below pi."""
    fisheye = load_scenario("mono_checkerboard", {"distortion_model": "equidistant",
                                                  "distortion": [0.0], "hfov_rad": 3.5})
    (camera,) = fisheye.cameras
    assert camera.model.fx == pytest.approx(320 / 1.75)
    with pytest.raises(ScenarioError, match="hfov_rad"):
        load_scenario("mono_checkerboard", {"hfov_rad": 3.5})
