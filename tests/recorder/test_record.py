"""record(): topics, camera_info, stamps, stereo truth, options and output formats."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from recorder.errors import RenderError
from recorder.record import _Pipeline, record
from recorder.render import SceneRenderer
from recorder.scenario import builtin_dir, load_scenario
from replay import FORMATS, Image, OutputError, open_reader
from tests.outputs import temp_outputs

from .logs import SCENARIO_TOPIC, Log, record_log, transform, translation

HFOV_RAD = 0.6
BASELINE_M = 0.02
RATE_HZ = 30.0
SMALL = {"width": 320, "height": 240}


def focal(width: int) -> float:
    """fx = fy = (W / 2) / tan(hfov / 2) for the built-in cameras."""
    return (width / 2) / math.tan(HFOV_RAD / 2)


# --- mono_checkerboard: the chapter's simple camera -----------------------------------------

@pytest.fixture(scope="module")
def mono(recording: Callable[..., Log]) -> Log:
    return recording("mono_checkerboard", frames=2)


def test_mono_topics_are_the_simple_camera_and_the_scenario(mono: Log) -> None:
    assert set(mono.topics) == {
        "/simple_camera/image_raw",
        "/simple_camera/camera_info",
        "/simple_camera/ground_truth/checkerboard",
        SCENARIO_TOPIC,
    }
    assert mono.counts == {topic: len(messages) for topic, messages in mono.topics.items()}
    assert sorted(mono.topics) == mono.result.topics


def test_mono_camera_info_is_the_ideal_640x480_camera(mono: Log) -> None:
    fx = 320 / math.tan(0.3)
    assert fx == pytest.approx(1034.47, abs=0.01)
    k = np.array([[fx, 0, 319.5], [0, fx, 239.5], [0, 0, 1]])
    infos = mono.infos("/simple_camera")
    assert len(infos) == 2
    for info in infos:
        assert (info.width, info.height) == (640, 480)
        assert info.distortion_model == "plumb_bob"
        np.testing.assert_array_equal(info.d, np.zeros(5))
        np.testing.assert_allclose(info.k, k, rtol=0, atol=1e-9)
        np.testing.assert_allclose(info.p, np.hstack([k, np.zeros((3, 1))]), rtol=0, atol=1e-9)
        np.testing.assert_array_equal(info.r, np.eye(3))
    # the scenario record carries the same model
    camera = mono.camera("simple_camera")
    np.testing.assert_allclose(camera["k"], k, rtol=0, atol=1e-9)
    assert camera["dropped_frames"] == []


def test_mono_images_are_640x480_rgb8_stamped_at_30_hz(mono: Log) -> None:
    images = mono.images("/simple_camera")
    assert len(images) == 2 == mono.result.frames["simple_camera"]
    for image in images:
        assert image.encoding == "rgb8"
        assert image.pixels.shape == (480, 640, 3)
        assert image.pixels.dtype == np.uint8
        assert image.pixels.std() > 10  # a scene, not a blank frame
    stamps = np.array([image.stamp_ns for image in images])
    np.testing.assert_allclose(np.diff(stamps), 1e9 / RATE_HZ, rtol=0, atol=1)
    infos = mono.infos("/simple_camera")
    truths = mono.truths("/simple_camera", "checkerboard")
    assert [m.stamp_ns for m in infos] == [m.stamp_ns for m in truths] == stamps.tolist()
    frame_ids = {m.frame_id for m in (*images, *infos, *truths)}
    assert frame_ids == {"simple_camera_optical_frame"}


# --- stereo_checkerboard: the synchronised rig ---------------------------------------------

@pytest.fixture(scope="module")
def stereo(recording: Callable[..., Log]) -> Log:
    # 16 frames span a hold boundary (the board moves after 15 frames)
    return recording("stereo_checkerboard", frames=16)


def test_stereo_projection_matrices_carry_the_baseline(stereo: Log) -> None:
    fx = focal(640)
    left = stereo.infos("/stereo_camera/left")
    right = stereo.infos("/stereo_camera/right")
    assert len(left) == len(right) == 16
    for info in left:
        assert info.p[0, 3] == 0.0
    for info in right:
        assert info.p[0, 3] == pytest.approx(-fx * BASELINE_M, abs=1e-9)
        np.testing.assert_array_equal(info.p[:, :3], info.k)
    assert right[0].p[0, 3] == pytest.approx(-20.69, abs=0.01)
    np.testing.assert_array_equal(left[0].k, right[0].k)


def test_stereo_stamps_are_identical(stereo: Log) -> None:
    left = [m.stamp_ns for m in stereo.images("/stereo_camera/left")]
    right = [m.stamp_ns for m in stereo.images("/stereo_camera/right")]
    assert len(left) == 16
    assert left == right
    assert len(set(left)) == len(left)


def test_stereo_truth_differs_by_the_baseline(stereo: Log) -> None:
    left = stereo.truths("/stereo_camera/left", "checkerboard")
    right = stereo.truths("/stereo_camera/right", "checkerboard")
    assert len(left) == len(right) == 16
    right_from_left = translation(x=-BASELINE_M)
    for left_pose, right_pose in zip(left, right, strict=True):
        assert left_pose.stamp_ns == right_pose.stamp_ns
        np.testing.assert_allclose(
            transform(right_pose), right_from_left @ transform(left_pose), rtol=0, atol=1e-9
        )
    # the board did move between the two holds
    assert not np.allclose(transform(left[0]), transform(left[15]))
    world_from_left = np.array(stereo.camera("left")["world_from_camera"])
    world_from_right = np.array(stereo.camera("right")["world_from_camera"])
    np.testing.assert_allclose(world_from_right, world_from_left @ translation(x=BASELINE_M),
                               atol=1e-12)


def test_cameras_at_different_rates_cover_the_same_span(
    recording: Callable[..., Log], tmp_path: Path
) -> None:
    """A 15 Hz right camera beside the 30 Hz left one records half as many frames over the
    same time, and the board moves for both until the end."""
    text = (builtin_dir() / "stereo_checkerboard.toml").read_text()
    assert text.count('relative_to = "left"') == 1
    spec = tmp_path / "mixed.toml"
    spec.write_text(text.replace('relative_to = "left"', 'relative_to = "left"\nrate_hz = 15.0'))
    scenario = load_scenario(str(spec), {"frames": 60, **SMALL})
    assert scenario.frame_counts == (60, 30)
    log = recording(spec, frames=60, **SMALL)
    left = [m.stamp_ns for m in log.images("/stereo_camera/left")]
    right = [m.stamp_ns for m in log.images("/stereo_camera/right")]
    assert (len(left), len(right)) == (60, 30)
    assert right == left[::2]  # same start, twice the period
    poses = log.truths("/stereo_camera/right", "checkerboard")
    # 0.5 s holds: the right camera's last second still sees new poses
    assert not np.allclose(transform(poses[-1]), transform(poses[-16]))


# --- options --------------------------------------------------------------------------------

def test_noise_has_the_requested_standard_deviation(recording: Callable[..., Log]) -> None:
    sigma = 4.0
    clean = recording("mono_checkerboard", frames=2, **SMALL).images("/simple_camera")
    noisy = recording("mono_checkerboard", frames=2, noise_std=sigma, **SMALL).images(
        "/simple_camera")
    for a, b in zip(clean, noisy, strict=True):
        assert a.stamp_ns == b.stamp_ns
        reference = a.pixels.astype(np.int16)
        diff = b.pixels.astype(np.int16) - reference
        # away from 0 and 255, so that clipping does not shrink the noise
        unclipped = (reference > 5 * sigma) & (reference < 255 - 5 * sigma)
        assert unclipped.sum() > 10_000  # the ground around the board: plenty of samples
        assert diff[unclipped].std() == pytest.approx(sigma, rel=0.15)
        assert abs(diff[unclipped].mean()) < 0.1 * sigma


@pytest.mark.parametrize("encoding", ["bgr8", "mono8"])
def test_encoding(recording: Callable[..., Log], encoding: str) -> None:
    rgb = recording("mono_checkerboard", frames=2, **SMALL).images("/simple_camera")
    other = recording("mono_checkerboard", frames=2, encoding=encoding, **SMALL).images(
        "/simple_camera")
    assert len(other) == len(rgb) == 2
    for a, b in zip(rgb, other, strict=True):
        assert b.encoding == encoding
        if encoding == "bgr8":
            np.testing.assert_array_equal(b.pixels, a.pixels[..., ::-1])
        else:
            assert b.pixels.shape == (240, 320)
            r, g, bl = (a.pixels[..., i].astype(np.float64) for i in range(3))
            luma = 0.299 * r + 0.587 * g + 0.114 * bl  # ITU-R BT.601
            assert np.abs(b.pixels - luma).max() <= 1.0


def test_resolution_override_moves_the_principal_point(recording: Callable[..., Log]) -> None:
    log = recording("mono_checkerboard", frames=2, **SMALL)
    fx = 160 / math.tan(HFOV_RAD / 2)
    for info in log.infos("/simple_camera"):
        assert (info.width, info.height) == (320, 240)
        np.testing.assert_allclose(info.k, [[fx, 0, 159.5], [0, fx, 119.5], [0, 0, 1]],
                                   rtol=0, atol=1e-9)
    assert all(i.pixels.shape == (240, 320, 3) for i in log.images("/simple_camera"))


def test_intrinsics_override(recording: Callable[..., Log]) -> None:
    fx, fy, cx, cy = 300.0, 320.0, 150.0, 125.0
    log = recording("mono_checkerboard", frames=1, intrinsics=[fx, fy, cx, cy], **SMALL)
    (info,) = log.infos("/simple_camera")
    np.testing.assert_array_equal(info.k, [[fx, 0, cx], [0, fy, cy], [0, 0, 1]])
    # a camera MuJoCo cannot render directly is warped from a supersampled render
    assert log.camera("simple_camera")["supersample"] == 2


@pytest.fixture(scope="module")
def format_reference(recording: Callable[..., Log]) -> Log:
    return recording("stereo_checkerboard", frames=3, **SMALL)


@pytest.mark.slow
@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_every_format_reads_back_the_same_messages(
    tmp_path: Path, fmt: str, format_reference: Log
) -> None:
    name = {"mcap": "log.mcap", "ros1": "log.bag"}.get(fmt, "log")
    log = record_log("stereo_checkerboard", tmp_path / name, fmt=fmt, frames=3, **SMALL)
    assert log.path.exists()
    assert temp_outputs(tmp_path) == []
    per_topic = {topic: len(messages) for topic, messages in log.topics.items()}
    assert log.counts == per_topic
    assert per_topic == {t: len(m) for t, m in format_reference.topics.items()}
    assert per_topic[SCENARIO_TOPIC] == 1
    for namespace in ("/stereo_camera/left", "/stereo_camera/right"):
        assert per_topic[f"{namespace}/image_raw"] == 3
        assert log.images(namespace) == format_reference.images(namespace)
        assert log.infos(namespace) == format_reference.infos(namespace)


# --- failures leave nothing behind ---------------------------------------------------------

def _writer_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "camlog-writer"]


def _fail_on_call(n: int, error: BaseException, original: Callable[..., Any]) -> Callable[..., Any]:
    calls = [0]

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        calls[0] += 1
        if calls[0] == n:
            raise error
        return original(*args, **kwargs)

    return wrapper


@pytest.mark.slow
@pytest.mark.parametrize("where", ["render", "write"])
def test_a_failure_mid_recording_leaves_no_output_and_no_thread(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, where: str
) -> None:
    error: BaseException
    if where == "render":
        error = RenderError("GL context lost")
        # the second render: the board's second held pose, frame 15 of 20
        monkeypatch.setattr(SceneRenderer, "render",
                            _fail_on_call(2, error, SceneRenderer.render))
    else:
        error = OSError("disk full")
        monkeypatch.setattr(_Pipeline, "_write", _fail_on_call(3, error, _Pipeline._write))
    output = tmp_path / "log.mcap"
    scenario = load_scenario("mono_checkerboard", {"frames": 20, "width": 64, "height": 48})
    with pytest.raises(type(error), match=str(error)):
        record(scenario, output, progress=False)
    assert list(tmp_path.iterdir()) == []
    assert _writer_threads() == []


@pytest.mark.slow
def test_record_refuses_to_overwrite(tmp_path: Path) -> None:
    output = tmp_path / "log.mcap"
    output.write_bytes(b"keep me")
    scenario = load_scenario("mono_checkerboard", {"frames": 1, "width": 64, "height": 48})
    with pytest.raises(OutputError, match="exists"):
        record(scenario, output, progress=False)
    assert output.read_bytes() == b"keep me"
    record(scenario, output, overwrite=True, progress=False)
    with open_reader(output) as reader:
        images = [r.message for r in reader.messages(["/simple_camera/image_raw"])]
    assert len(images) == 1 and isinstance(images[0], Image)
    assert images[0].pixels.shape == (48, 64, 3)
