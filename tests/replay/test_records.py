"""Typed records of the well-known topics: exact JSON round trips, clear errors on bad JSON."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from replay import RecordError, Text, open_reader
from replay.records import (
    CalibrationSummary,
    ResyncStats,
    Scenario,
    ViewResiduals,
)
from replay.topics import SCENARIO, CameraTopics, ResyncTopics, read_record, split_ground_truth

from .samples import write_log

GOLDEN = Path(__file__).resolve().parents[2] / "datasets" / "golden"


@pytest.mark.parametrize("log", sorted(GOLDEN.glob("*.mcap")), ids=lambda p: p.name.split("-")[0])
def test_scenario_record_round_trips_the_recorders_json_byte_for_byte(log: Path) -> None:
    with open_reader(log) as reader:
        (stored,) = (r.message for r in reader.messages([SCENARIO]))
        scenario = read_record(reader, SCENARIO, Scenario)
    assert isinstance(stored, Text) and scenario is not None
    assert scenario.to_message() == stored
    raw = json.loads(stored.data)
    camera = scenario.cameras[0]
    assert camera.k.shape == (3, 3) and camera.world_from_camera.shape == (4, 4)
    np.testing.assert_array_equal(camera.k, raw["cameras"][0]["k"])
    assert camera.model().fx == raw["cameras"][0]["k"][0][0]
    assert camera.parameters()["cy"] == raw["cameras"][0]["k"][1][2]
    points = scenario.targets[0].points_in_target()
    assert points is not None and points.shape[1] == 3


def test_scenario_camera_is_found_by_namespace_then_unique_frame(tmp_path: Path) -> None:
    log = GOLDEN / "stereo_unsynced-seed0-640x480-f240.mcap"
    with open_reader(log) as reader:
        scenario = read_record(reader, SCENARIO, Scenario)
    assert scenario is not None
    left, right = scenario.cameras
    assert scenario.camera_for(left.namespace) is left
    assert scenario.camera_for("/stereo_sync/right", right.frame_id) is right
    assert scenario.camera_for("/nowhere", "no_frame") is None


def test_box_target_points_are_its_vertices() -> None:
    with open_reader(GOLDEN / "red_block-seed0-640x480-f10.mcap") as reader:
        scenario = read_record(reader, SCENARIO, Scenario)
    assert scenario is not None
    (box,) = scenario.targets
    points = box.points_in_target()
    assert box.kind == "box" and points is not None and points.shape == (8, 3)
    np.testing.assert_allclose(np.abs(points).max(axis=0), np.asarray(box.size_m) / 2)


@pytest.mark.parametrize(("text", "needle"), [
    ("{", "not valid JSON"),
    ("[]", "expected an object"),
    ('{"scenario": "x"}', "source: missing"),
    (json.dumps({"scenario": "x", "source": "s", "seed": "7", "camlog_version": "",
                 "mujoco_version": "", "renderer": "", "spec": {}, "cameras": [],
                 "targets": []}), "seed: expected an integer"),
    (json.dumps({"scenario": "x", "source": "s", "seed": 1, "camlog_version": "",
                 "mujoco_version": "", "renderer": "", "spec": {},
                 "cameras": [{"name": "c"}], "targets": []}), "cameras[0].namespace: missing"),
])
def test_malformed_scenario_says_what_and_where(tmp_path: Path, text: str, needle: str) -> None:
    log = tmp_path / "bad.mcap"
    write_log(log, [(SCENARIO, 1, Text(text))])
    with open_reader(log) as reader, pytest.raises(RecordError) as raised:
        read_record(reader, SCENARIO, Scenario)
    message = str(raised.value)
    assert needle in message and str(log) in message and SCENARIO in message
    assert "\n" not in message


def test_residuals_record_checks_its_shapes() -> None:
    view = ViewResiduals(5, "f", 0.1, np.array([[1.0, 2], [3, 4]]), np.array([[0.1, 0], [0, 0.2]]),
                         outliers=[1])
    again = ViewResiduals.from_message(view.to_message())
    assert again.stamp_ns == 5 and again.corners_px.shape == (2, 2) and again.outliers == [1]
    np.testing.assert_array_equal(again.residuals_px, view.residuals_px)
    assert json.loads(view.to_message().data) == {
        "stamp_ns": 5, "frame_id": "f", "rms_px": 0.1, "corners_px": [[1, 2], [3, 4]],
        "residuals_px": [[0.1, 0], [0, 0.2]], "outliers": [1], "until_ns": None}
    held = ViewResiduals(5, "f", 0.1, np.zeros((1, 2)), np.zeros((1, 2)), until_ns=70)
    assert ViewResiduals.from_message(held.to_message()).until_ns == 70
    with pytest.raises(RecordError, match="1 corners but 2 residuals"):
        ViewResiduals.from_json_text(json.dumps({
            "stamp_ns": 5, "frame_id": "f", "rms_px": 0.1, "corners_px": [[1, 2]],
            "residuals_px": [[0, 0], [0, 0]]}))
    with pytest.raises(RecordError, match="frame_id: missing"):
        ViewResiduals.from_json_text('{"stamp_ns": 5}')


def _camera(**extra: object) -> dict[str, object]:
    return {"namespace": "/c", "image_topic": "/c/image_raw", "width": 64, "height": 48,
            "frames": 10, "distinct_frames": 8, "boards_found": 7, "candidate_views": 6,
            "selected_views": 6, "used_views": 5,
            "rejected": [{"stamp_ns": 3, "reason": "blurred"}], "rms_px": 0.12,
            "distortion_model": "plumb_bob",
            "parameters": {"fx": {"value": 50.0, "std": 0.1, "truth": 50.5, "error": -0.5},
                           "k3": {"value": 0.0, "std": 0.0}},
            "cross_validation_px": None, "tangential": {"estimated": False},
            "coverage": {"X": {"min": 0.1, "max": 0.9, "progress": 1.0}, "image_cells": 0.75},
            **extra}


def test_calibration_summary_keeps_keys_order_and_optional_fields() -> None:
    data = {"board": {"pattern": "chessboard", "cols": 7, "rows": 6, "square_m": 0.01},
            "options": {"fix_principal_point": False, "fix_aspect_ratio": False,
                        "tangential": "auto", "k_coefficients": 2,
                        "distortion_model": "plumb_bob"},
            "cameras": [_camera(max_projection_difference_vs_truth_px=0.2)],
            "ground_truth": True}
    text = json.dumps(data, indent=1)
    summary = CalibrationSummary.from_json_text(text)
    assert summary.to_json_text(indent=1) == text
    (camera,) = summary.cameras
    assert camera.has_truth and camera.parameters["k3"].truth is None
    assert camera.coverage.ranges["X"].progress == 1.0 and camera.coverage.image_cells == 0.75
    assert summary.stereo is None
    assert summary.rejected_stamps() == {"/c": {3: "blurred"}}


def test_a_circle_grid_summary_keeps_its_diameter() -> None:
    board = {"pattern": "acircles", "cols": 4, "rows": 11, "square_m": 0.01,
             "diameter_m": 0.01002, "diameter_measured": True}
    text = json.dumps({"board": board,
                       "options": {"fix_principal_point": False, "fix_aspect_ratio": False,
                                   "tangential": "auto", "k_coefficients": 2,
                                   "distortion_model": "plumb_bob"},
                       "cameras": [_camera()], "ground_truth": False}, indent=1)
    summary = CalibrationSummary.from_json_text(text)
    assert summary.to_json_text(indent=1) == text
    assert summary.board.diameter_m == 0.01002 and summary.board.diameter_measured is True


def test_resync_stats_round_trip() -> None:
    text = json.dumps({
        "pairs": 3, "slop_ns": 16, "stamp_policy": "later of the two stamps", "left_frames": 4,
        "right_frames": 3, "left_unpaired_stamps_ns": [7], "right_unpaired_stamps_ns": [],
        "offset_right_minus_left_ns": {"min": -1, "median": 0, "max": 2},
        "left_topic": "/l", "right_topic": "/r", "slop_source": "given"})
    stats = ResyncStats.from_json_text(text)
    assert stats.offset_right_minus_left_ns is not None
    assert stats.offset_right_minus_left_ns.max == 2 and stats.peak_buffered_messages is None
    assert stats.to_json_text() == text


def test_topic_names() -> None:
    left = CameraTopics("/stereo/left/")
    assert (left.image_raw, left.camera_info, left.ground_truth("board")) == (
        "/stereo/left/image_raw", "/stereo/left/camera_info", "/stereo/left/ground_truth/board")
    assert (left.detections, left.residuals, left.view_error, left.calibrated_info,
            left.image_rect) == (
        "/stereo/left/calibration/detections", "/stereo/left/calibration/residuals",
        "/stereo/left/calibration/view_error", "/stereo/left/calibrated/camera_info",
        "/stereo/left/image_rect")
    assert split_ground_truth(left.ground_truth("board")) == ("/stereo/left", "board")
    assert split_ground_truth("/a/ground_truth/b/c") is None
    synced = ResyncTopics()
    assert (synced.left.image_raw, synced.offset, synced.stats) == (
        "/stereo_sync/left/image_raw", "/stereo_sync/offset_s", "/stereo_sync/stats")
