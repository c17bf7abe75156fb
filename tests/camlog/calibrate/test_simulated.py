"""The calibration flow on simulated recordings, judged against the simulator's ground truth,
and what it writes (calibration files, report, figures, the annotated log).

Each test calls :func:`camlog.calibrate.flow.calibrate_log` with a request and reads the
summary it returns; the command line's own behaviour (its one-line errors, ``--check``'s
output) is tested in ``tests/camlog/cli/test_calibrate.py``.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from camlog.logs.convert import convert_log
from camlog.processing.resync_log import resync_log
from camlog.requests.logs import ConvertRequest
from camlog.requests.processing import ResyncRequest
from replay import CameraInfo, PoseStamped, open_reader
from replay.calibration_yaml import load_calibration
from replay.camera import CameraModel
from replay.geometry import rotation_from_quat_xyzw
from replay.records import ParameterEstimate
from tests.camlog.conftest import LEFT, Calibrated, calibrate, scenario

#: every simulated camera: 640 px wide, 0.6 rad horizontal field of view, no skew
FOCAL_PX = 320 / math.tan(0.3)
BASELINE_M = 0.02
FIGURES = ["coverage.png", "view_errors.png", "residuals.png", "uncertainty.png"]


def true_model(log: Path, namespace: str) -> CameraModel:
    """A camera's model as the simulator rendered it."""
    (camera,) = (c for c in scenario(log)["cameras"] if c["namespace"] == namespace)
    return CameraModel(camera["width"], camera["height"], np.array(camera["k"]),
                       camera["distortion_model"], np.array(camera["d"]))


def true_parameters(model: CameraModel) -> dict[str, float]:
    """The intrinsics and distortion coefficients of a model, by name."""
    names = ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"]
    return {"fx": model.fx, "fy": model.fy, "cx": model.cx, "cy": model.cy,
            **dict(zip(names, model.d.tolist(), strict=False))}


def assert_within_3_sigma(parameters: dict[str, ParameterEstimate],
                          truth: dict[str, float]) -> None:
    """Every estimated parameter (std > 0) lies within 3 sigma of its true value."""
    estimated = {n: p for n, p in parameters.items() if p.std > 0}
    assert {"fx", "fy", "cx", "cy", "k1", "k2"} <= set(estimated)
    for name, p in estimated.items():
        assert abs(p.value - truth[name]) < 3 * p.std, f"{name}: {p} vs {truth[name]}"


# --- calibrations shared by the tests ---------------------------------------------------------

@pytest.fixture(scope="module")
def out_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("calibrate")


@pytest.fixture(scope="module")
def mono_tangent(rig_log: Path, out_dir: Path) -> Calibrated:
    return calibrate(rig_log, out_dir / "mono_tangent", camera=(LEFT,), tangent_dist=True)


@pytest.fixture(scope="module")
def mono_zero_tangent(rig_log: Path, out_dir: Path) -> Calibrated:
    return calibrate(rig_log, out_dir / "mono_zero_tangent", camera=(LEFT,),
                     zero_tangent_dist=True)


@pytest.fixture(scope="module")
def plumb_bob(plumb_bob_log: Path, out_dir: Path) -> Calibrated:
    return calibrate(plumb_bob_log, out_dir / "plumb_bob")


@pytest.fixture(scope="module")
def approximate(unsynced_log: Path, out_dir: Path) -> Calibrated:
    return calibrate(unsynced_log, out_dir / "approximate", left="/unsynced/left",
                     right="/unsynced/right", approximate=0.02)


# --- accuracy against the simulator -----------------------------------------------------------

def test_mono_focal_length(rig_left: Calibrated, rig_log: Path) -> None:
    truth = true_model(rig_log, LEFT)
    assert truth.fx == truth.fy == pytest.approx(FOCAL_PX, rel=1e-12)
    p = rig_left.camera(LEFT).parameters
    for name in ("fx", "fy"):
        assert p[name].value == pytest.approx(FOCAL_PX, rel=0.001)


@pytest.mark.parametrize("calibration", ["rig_left", "mono_tangent"])
def test_mono_every_parameter_within_3_sigma(calibration: str, rig_log: Path,
                                             request: pytest.FixtureRequest) -> None:
    truth = true_parameters(true_model(rig_log, LEFT))
    camera = request.getfixturevalue(calibration).camera(LEFT)
    for name, p in camera.parameters.items():
        assert p.truth == truth[name]  # the summary's truth is the scenario's
    assert_within_3_sigma(camera.parameters, truth)
    estimated = calibration == "mono_tangent"
    assert (camera.parameters["p1"].std > 0) == estimated
    assert camera.tangential.estimated == estimated


def test_default_drops_tangential_distortion_the_lens_does_not_have(
    rig_left: Calibrated, mono_tangent: Calibrated
) -> None:
    camera = rig_left.camera(LEFT)
    p = camera.parameters
    assert p["p1"].value == p["p2"].value == 0.0
    test = camera.tangential
    assert test.p_value is not None and test.chi2 is not None and test.summary is not None
    assert test.p_value >= 1e-3 and test.chi2 < 13.9
    assert "held at zero" in test.summary
    assert "held at zero" in (rig_left.folder / "report.md").read_text()
    assert mono_tangent.camera(LEFT).tangential.chi2 is None
    # what the terms left out (p1 p2, and k3 beside the k1 k2 the views chose) would change
    # is stated in the uncertainty
    u = camera.uncertainty
    assert u is not None and u.left_out_worst_px is not None
    assert 0 < u.left_out_worst_px <= u.rays_worst_px
    assert "leaves out" in (rig_left.folder / "report.md").read_text()
    # without p1, p2 to trade against, the principal point is pinned down better
    free = mono_tangent.camera(LEFT).parameters
    for name, centre in (("cx", 319.5), ("cy", 239.5)):
        assert p[name].std < free[name].std
        assert abs(p[name].value - centre) < 0.5


def test_mono_zero_tangent_principal_point(mono_zero_tangent: Calibrated) -> None:
    p = mono_zero_tangent.camera(LEFT).parameters
    assert p["p1"].value == p["p2"].value == 0.0
    # an ideal 640x480 camera's principal point is the image centre (pixel centres integer)
    assert abs(p["cx"].value - 319.5) < 0.5
    assert abs(p["cy"].value - 239.5) < 0.5
    assert p["fx"].value == pytest.approx(FOCAL_PX, rel=0.001)


def test_plumb_bob_lens(plumb_bob: Calibrated, plumb_bob_log: Path) -> None:
    truth = true_model(plumb_bob_log, "/simple_camera")
    np.testing.assert_array_equal(truth.d, [-0.2, 0.05, 0, 0, 0])
    camera = plumb_bob.camera("/simple_camera")
    p = camera.parameters
    assert abs(p["k1"].value + 0.2) < 3 * p["k1"].std
    assert p["fx"].value == pytest.approx(FOCAL_PX, rel=0.001)
    assert_within_3_sigma(p, true_parameters(truth))
    # measured 0.32 px with this seed; the principal point's own sigma is about 0.5 px
    assert camera.max_projection_difference_vs_truth_covered_px is not None
    assert camera.max_projection_difference_vs_truth_covered_px < 0.4


def test_stereo_rig(rig_stereo: Calibrated) -> None:
    s, folder = rig_stereo.summary.stereo, rig_stereo.folder
    assert s is not None and s.truth is not None
    assert s.baseline_m == pytest.approx(BASELINE_M, rel=0.002)
    assert s.truth.baseline_m == pytest.approx(BASELINE_M, rel=1e-9)
    assert s.epipolar_rms_px < 0.1
    assert s.square_m == pytest.approx(0.01, rel=0.01)
    assert s.rotation_deg < 0.05  # the spec turns neither camera
    left, right = (load_calibration(folder / f"{side}.yaml").camera_info
                   for side in ("left", "right"))
    assert left.p[0, 3] == 0.0
    # P2[0, 3] = -fx' * B: the right camera sits B along the left camera's +x
    assert right.p[0, 3] < 0
    assert right.p[0, 3] == pytest.approx(-right.p[0, 0] * BASELINE_M, rel=0.005)
    np.testing.assert_allclose(left.p[:, :3], right.p[:, :3])
    rectified = cv2.imread(str(folder / "rectified.png"))
    assert rectified is not None and rectified.shape[1] == 2 * 640
    text = (folder / "ost.txt").read_text()
    assert "[narrow_stereo/left]" in text and "[narrow_stereo/right]" in text
    for side in ("left", "right"):
        for figure in FIGURES:
            assert (folder / f"{side}_{figure}").is_file()
    # every joint view is rectified on both sides, also where one side repeats a frame
    with open_reader(folder / "calibration.mcap") as reader:
        counts = {side: reader.topics[f"/stereo_camera/{side}/image_rect"].count
                  for side in ("left", "right")}
    assert counts["left"] == counts["right"] == s.joint_views


def test_transposed_size_is_the_same_board(plumb_bob: Calibrated, plumb_bob_log: Path,
                                           tmp_path: Path) -> None:
    """A 7x6 board turned by 90° is a 6x7 board: OpenCV finds it either way round, and the
    camera comes out the same (only the board frame turns)."""
    turned = calibrate(plumb_bob_log, tmp_path / "turned", size="6x7")
    a, b = plumb_bob.camera("/simple_camera"), turned.camera("/simple_camera")
    assert b.used_views == a.used_views
    for name, p in a.parameters.items():
        # the same solution, up to where the solver stopped: far inside its uncertainty
        assert abs(b.parameters[name].value - p.value) <= 0.01 * p.std


# --- the same camera stored otherwise --------------------------------------------------------

def left_camera_as(rig_log: Path, output: Path, **conversion: Any) -> Path:
    """The rig's left camera (and the scenario record) converted into ``output``."""
    with open_reader(rig_log) as reader:
        topics = [t for t in reader.topics if t.startswith(LEFT) or t == "/camlog/scenario"]
    convert_log(ConvertRequest(input=rig_log, output=output, topics=tuple(topics),
                               progress=False, **conversion))
    return output


def test_foxglove_camera_calibrates_like_the_ros_one(rig_left: Calibrated, rig_log: Path,
                                                    out_dir: Path) -> None:
    """The left camera stored as foxglove.RawImage + foxglove.CameraCalibration (protobuf)
    gives the same calibration as its sensor_msgs form."""
    fox = left_camera_as(rig_log, out_dir / "fox.mcap", profile="foxglove")
    with open_reader(fox) as reader:
        assert reader.topics[f"{LEFT}/image_raw"].msgtype == "foxglove.RawImage"
        assert reader.topics[f"{LEFT}/camera_info"].msgtype == "foxglove.CameraCalibration"
    calibrated = calibrate(fox, out_dir / "fox", camera=(LEFT,))
    ros = load_calibration(rig_left.folder / "ost.yaml").camera_info
    fox_info = load_calibration(calibrated.folder / "ost.yaml").camera_info
    assert fox_info.distortion_model == ros.distortion_model
    # equal up to floating-point summation order (detections are gathered from threads),
    # which the least-squares solve amplifies in weakly determined coefficients (k2, k3) to
    # ~1e-7 relative: still 1e5 times below their standard deviation
    for name in ("k", "d", "r", "p"):
        np.testing.assert_allclose(getattr(fox_info, name), getattr(ros, name), rtol=1e-6,
                                   atol=1e-9)


def test_h264_camera_calibrates_close_to_the_raw_one(rig_left: Calibrated, rig_log: Path,
                                                     out_dir: Path) -> None:
    """The left camera stored as foxglove.CompressedVideo H.264 (``convert --compress h264``)
    calibrates to the raw images' result within its uncertainty: the codec moves corners
    by small fractions of a pixel."""
    video = left_camera_as(rig_log, out_dir / "video.mcap", compress="h264")
    with open_reader(video) as reader:
        assert reader.topics[f"{LEFT}/image_raw/video"].msgtype == "foxglove.CompressedVideo"
        assert f"{LEFT}/image_raw" not in reader.topics
    raw = rig_left.camera(LEFT)
    coded = calibrate(video, out_dir / "video", camera=(LEFT,)).camera(LEFT)
    assert coded.image_topic == f"{LEFT}/image_raw/video"
    assert coded.frames == raw.frames  # every picture decoded
    assert coded.used_views == pytest.approx(raw.used_views, abs=2)
    for name, p in raw.parameters.items():
        if p.std > 0:
            assert abs(coded.parameters[name].value - p.value) < 3 * p.std, name
    assert_within_3_sigma(coded.parameters, true_parameters(true_model(rig_log, LEFT)))


# --- what the calibration writes ---------------------------------------------------------------

def test_yaml_matches_the_summary(rig_left: Calibrated) -> None:
    info = load_calibration(rig_left.folder / "ost.yaml").camera_info
    p = rig_left.camera(LEFT).parameters
    assert (info.width, info.height) == (640, 480)
    np.testing.assert_allclose(info.k, [[p["fx"].value, 0, p["cx"].value],
                                        [0, p["fy"].value, p["cy"].value], [0, 0, 1]],
                               rtol=1e-12)
    assert info.distortion_model == "plumb_bob"
    np.testing.assert_allclose(info.d, [p[n].value for n in ("k1", "k2", "p1", "p2", "k3")],
                               rtol=1e-12, atol=1e-15)
    text = (rig_left.folder / "ost.txt").read_text()
    assert "[image]" in text and "[narrow_stereo]" in text
    # calibration.json holds the summary the flow returned
    assert json.loads((rig_left.folder / "calibration.json").read_text()) == \
        json.loads(rig_left.summary.to_json_text())


def test_no_report_writes_the_same_calibration_alone(rig_left: Calibrated, rig_log: Path,
                                                     out_dir: Path) -> None:
    bare = calibrate(rig_log, out_dir / "mono_no_report", camera=(LEFT,), report=False)
    assert sorted(f.name for f in bare.folder.iterdir()) == ["calibration.json", "ost.txt",
                                                             "ost.yaml"]
    # the same solve (equal up to the last bits: OpenCV's threads add in any order)
    np.testing.assert_allclose(load_calibration(bare.folder / "ost.yaml").camera_info.k,
                               load_calibration(rig_left.folder / "ost.yaml").camera_info.k,
                               rtol=1e-6)
    full, alone = rig_left.camera(LEFT), bare.camera(LEFT)
    assert alone.used_views == full.used_views
    for name, parameter in full.parameters.items():
        assert alone.parameters[name].value == pytest.approx(parameter.value, rel=1e-6,
                                                             abs=1e-9)
    # the same keys in the written summary, with and without the report
    written = [json.loads((c.folder / "calibration.json").read_text()) for c in (bare, rig_left)]
    assert written[0].keys() == written[1].keys()
    assert written[0]["cameras"][0].keys() == written[1]["cameras"][0].keys()


def digests(log: Path, topics: list[str]) -> dict[str, list[tuple[int, str]]]:
    out: dict[str, list[tuple[int, str]]] = {t: [] for t in topics}
    with open_reader(log) as reader:
        for raw in reader.raw_messages(topics):
            out[raw.topic].append((raw.log_time_ns, hashlib.sha256(raw.data).hexdigest()))
    return out


def decoded(log: Path, topic: str) -> list[Any]:
    with open_reader(log) as reader:
        return [record.message for record in reader.messages([topic])]


def distinct_stamps(log: Path, topic: str) -> tuple[list[int], int]:
    """Image stamps, and how many images differ from the one before (a held board repeats)."""
    stamps, distinct, previous = [], 0, None
    with open_reader(log) as reader:
        for record in reader.frames([topic]):
            stamps.append(record.message.stamp_ns)
            if previous is None or not np.array_equal(previous, record.message.pixels):
                distinct += 1
            previous = record.message.pixels
    return stamps, distinct


def test_calibrated_log_keeps_the_input_and_adds_the_evidence(rig_left: Calibrated,
                                                              rig_log: Path) -> None:
    out = rig_left.folder / "calibration.mcap"
    with open_reader(rig_log) as reader:
        topics = {name: info.count for name, info in reader.topics.items()}
    with open_reader(out) as reader:
        counts = {name: info.count for name, info in reader.topics.items()}
    assert {t: counts[t] for t in topics} == topics
    assert digests(out, list(topics)) == digests(rig_log, list(topics))  # the same bytes

    stamps, distinct = distinct_stamps(rig_log, f"{LEFT}/image_raw")
    assert distinct < len(stamps)  # held poses repeat frames
    assert counts[f"{LEFT}/calibration/detections"] == distinct

    yaml = load_calibration(rig_left.folder / "ost.yaml").camera_info
    infos = decoded(out, f"{LEFT}/calibrated/camera_info")
    assert [i.stamp_ns for i in infos] == stamps
    for info in infos:
        assert isinstance(info, CameraInfo)
        np.testing.assert_array_equal(info.k, yaml.k)
        np.testing.assert_array_equal(info.d, yaml.d)

    residuals = [json.loads(m.data) for m in decoded(out, f"{LEFT}/calibration/residuals")]
    assert len(residuals) == rig_left.camera(LEFT).used_views >= 50
    assert {r["stamp_ns"] for r in residuals} <= set(stamps)
    for r in residuals:
        corners, res = np.array(r["corners_px"]), np.array(r["residuals_px"])
        assert corners.shape == res.shape == (42, 2)
        inliers = np.ones(42, dtype=bool)
        inliers[r["outliers"]] = False  # corners left out as outliers
        assert inliers.sum() >= 21
        assert math.sqrt(np.mean(np.sum(res[inliers] ** 2, axis=1))) == \
            pytest.approx(r["rms_px"], rel=1e-3)
    (stored,) = decoded(out, "/calibration/summary")
    assert json.loads(stored.data) == json.loads(rig_left.summary.to_json_text())


def test_report_and_figures(rig_left: Calibrated) -> None:
    camera = rig_left.camera(LEFT)
    report = (rig_left.folder / "report.md").read_text()
    assert "truth" in report
    # the image corners the held boards never reached: where, and the figure there
    u = camera.uncertainty
    assert u is not None and u.beyond_boards_line is not None
    assert u.beyond_boards_px is not None and u.beyond_boards_share is not None
    assert 0 < u.beyond_boards_share < 1 and u.beyond_boards_px <= max(u.worst_px,
                                                                      u.rays_worst_px)
    assert "corners" in (u.beyond_boards_where or "")
    assert u.beyond_boards_line[1:] in report
    assert camera.max_projection_difference_vs_truth_covered_px is not None
    assert f"{camera.max_projection_difference_vs_truth_covered_px:.3f} px" in report
    for name in ("fx", "cx", "k1"):
        row = next(line for line in report.splitlines() if line.startswith(f"| {name} |"))
        error = camera.parameters[name].error
        assert error is not None
        assert f"{error:+.4g}" in row  # error against the truth
    for figure in FIGURES:
        assert f"({figure})" in report
        image = cv2.imread(str(rig_left.folder / figure))
        assert image is not None and image.ndim == 3 and min(image.shape[:2]) > 200
        assert image.std() > 5  # not a blank canvas
        colours = np.unique(image.reshape(-1, 3), axis=0)
        assert len(colours) > 20


# --- partial views and unsynchronised rigs -----------------------------------------------------

def camera_from_board(pose: PoseStamped) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = rotation_from_quat_xyzw(pose.orientation_xyzw)
    out[:3, 3] = pose.position_m
    return out


def test_no_accepted_view_is_wrong(approximate: Calibrated, unsynced_log: Path) -> None:
    """The board is cut by the image border in 30 % of the poses; every view the calibration
    used has its corners where the simulator put them."""
    (target,) = scenario(unsynced_log)["targets"]
    points = np.array(target["corners_in_target"])
    cols, rows = target["inner_corners"]
    s = target["square_m"]
    outline = np.array([[-s, -s, 0], [cols * s, -s, 0], [cols * s, rows * s, 0],
                        [-s, rows * s, 0]])
    out = approximate.folder / "calibration.mcap"
    for ns in ("/unsynced/left", "/unsynced/right"):
        model = true_model(unsynced_log, ns)
        poses = {p.stamp_ns: camera_from_board(p)
                 for p in decoded(unsynced_log, f"{ns}/ground_truth/checkerboard")}

        def project(pose: np.ndarray, xyz: np.ndarray, m: CameraModel = model) -> np.ndarray:
            return m.project(xyz @ pose[:3, :3].T + pose[:3, 3])

        cut = sum(
            not ((uv >= 0).all() and (uv[:, 0] <= 639).all() and (uv[:, 1] <= 479).all())
            for uv in (project(p, outline) for p in poses.values()))
        assert cut >= 5, "the recording should show boards cut by the border"
        used = [json.loads(m.data) for m in decoded(out, f"{ns}/calibration/residuals")]
        assert len(used) >= 10
        for view in used:
            corners = np.array(view["corners_px"])
            truth = project(poses[view["stamp_ns"]], points)
            # OpenCV may start from either end of a board: its 180° turn is the same grid
            error = min(np.abs(corners - truth).max(), np.abs(corners - truth[::-1]).max())
            assert error < 0.5, f"{ns} view at {view['stamp_ns']}: {error:.2f} px"


def test_unsynced_rig_with_approximate_pairing(approximate: Calibrated) -> None:
    s = approximate.summary.stereo
    assert s is not None
    assert s.baseline_m == pytest.approx(BASELINE_M, rel=0.005)
    assert s.epipolar_rms_px < 0.1


def test_resynced_rig_calibrates(unsynced_log: Path, tmp_path: Path) -> None:
    synced = tmp_path / "synced.mcap"
    resync_log(ResyncRequest(log=unsynced_log, output=synced, progress=False))
    calibrated = calibrate(synced, tmp_path / "out", left="/stereo_sync/left",
                           right="/stereo_sync/right")
    s = calibrated.summary.stereo
    assert s is not None and s.truth is not None
    # resync renames the topics but keeps the frame ids, by which the truth is still found
    assert s.truth.baseline_m == pytest.approx(BASELINE_M, rel=1e-9)
    assert abs(s.truth.baseline_error_percent) < 0.5
    assert all(c.parameters["fx"].truth is not None for c in calibrated.summary.cameras)
    assert s.baseline_m == pytest.approx(BASELINE_M, rel=0.005)
    assert s.epipolar_rms_px < 0.1
