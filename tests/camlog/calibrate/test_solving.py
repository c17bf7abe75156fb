"""The radial order in the flow: by default (or with ``-k auto``) it is chosen per camera and
every output says so; an order given (``-k N``, ``--model``) is solved as given, without a
choice. The board's warp likewise: cross-validated by default, as given with --board-warp."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pytest

from camlog.calibrate.flow import calibrate_log
from camlog.cli import build_parser
from camlog.requests.arguments import request_from_args
from camlog.requests.calibrate import CalibrateRequest
from processors.calibration.model_order import order_label


def request(log: Path, out: Path, *flags: str) -> CalibrateRequest:
    parser = build_parser(["calibrate"])
    args: argparse.Namespace = parser.parse_args(
        ["calibrate", str(log), "-s", "7x6", "-q", "0.01", "--camera", "/simple_camera",
         "-o", str(out), "--no-progress", "--no-report", *flags])
    return request_from_args(CalibrateRequest, args)


@pytest.mark.parametrize("flags", [(), ("-k", "auto")])
def test_the_order_is_chosen_and_reported(mono_calibration_log: Path, tmp_path: Path,
                                          flags: tuple[str, ...]) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"  # 320x240, an ideal lens
    run = calibrate_log(request(log, tmp_path / "auto", *flags))
    order = run.cameras[0].order
    assert order is not None and order.folds == 5 and order.views >= 10
    assert order_label(order.options) == "plumb_bob k1 k2"  # the lens has no k3
    assert run.solved.joint.options[0].radial_count == 2
    # nor beyond the views: k1 k2 hold their figure there, and k3's fit is what they leave out
    assert order.beyond_ratio is not None and order.beyond_ratio <= 1.0
    (left_out,) = run.solved.joint.left_out_models
    assert left_out is not None and left_out.d[4] != 0.0
    u = run.summary.cameras[0].uncertainty
    assert u is not None and u.left_out_worst_px is not None
    written = json.loads((tmp_path / "auto" / "calibration.json").read_text())
    camera = written["cameras"][0]
    assert camera["lens_order"]["chosen"] == "plumb_bob k1 k2"
    # k3 not taken: the ladder stops below rational_polynomial
    assert camera["lens_order"]["candidates"] == ["plumb_bob k1 k2", "plumb_bob k1 k2 k3"]
    assert len(camera["lens_order"]["held_out_rms_px"]) == 2
    assert written["options"]["choose_order"] is True


@pytest.mark.parametrize(("flags", "radial"), [(("-k", "3"), 3), (("-k", "2"), 2),
                                              (("--model", "plumb_bob"), 2)])
def test_an_order_given_is_not_chosen(mono_calibration_log: Path, tmp_path: Path,
                                      flags: tuple[str, ...], radial: int) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"
    run = calibrate_log(request(log, tmp_path / "given", *flags))
    assert run.cameras[0].order is None
    assert run.solved.joint.options[0].radial_count == radial
    written = json.loads((tmp_path / "given" / "calibration.json").read_text())
    assert "lens_order" not in written["cameras"][0]
    assert "choose_order" not in written["options"]


def test_the_board_warp_is_cross_validated_and_reported(mono_calibration_log: Path,
                                                        tmp_path: Path) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"  # a simulated, flat board
    run = calibrate_log(request(log, tmp_path / "auto"))
    choice = run.solved.joint.warp_choice
    assert choice is not None and choice.folds == 5 and not choice.chosen
    assert run.solved.joint.board_warp_m is None
    written = json.loads((tmp_path / "auto" / "calibration.json").read_text())
    warp = written["board_warp"]
    assert warp["mode"] == "auto" and warp["estimated"] is False and "warp_mm" not in warp
    assert len(warp["held_out_rms_px"]) == 2 and warp["views"] == choice.views
    assert warp["summary"].startswith("board held flat by cross-validation")


@pytest.mark.parametrize("mode", ["on", "off"])
def test_a_board_warp_given_is_not_chosen(mono_calibration_log: Path, tmp_path: Path,
                                          mode: str) -> None:
    log = mono_calibration_log.parent.parent / "mono.mcap"
    run = calibrate_log(request(log, tmp_path / mode, "--board-warp", mode))
    assert run.solved.joint.warp_choice is None
    written = json.loads((tmp_path / mode / "calibration.json").read_text())
    if mode == "off":
        assert run.solved.joint.board_warp_m is None and "board_warp" not in written
        return
    estimate = run.solved.joint.board_warp_m
    assert estimate is not None
    warp_m, std_m = estimate
    assert np.all(np.abs(warp_m) < 4 * std_m)  # the simulated board is flat
    assert written["board_warp"]["warp_std_mm"] == pytest.approx((1000 * std_m).tolist())
    assert written["board_warp"]["summary"].startswith("board warp ")
