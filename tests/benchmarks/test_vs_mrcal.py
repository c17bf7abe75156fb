"""The mrcal comparison's statistics, table, arguments and mrcal plumbing, on synthetic numbers
(no mrcal needed)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from benchmarks.calibration_truth import Accuracy, accuracy
from benchmarks.mrcal_run import MrcalError, mrcal_available, parse_answer
from benchmarks.mrcal_solve import corners_vnl
from benchmarks.spread import spread, table
from benchmarks.vs_mrcal import (
    CASES,
    Progress,
    default_flags,
    models_line,
    parse_arguments,
    recording,
)
from replay.camera import CameraModel


def mono(fx: float, max_px: float) -> Accuracy:
    return Accuracy(fx, 0.1, -0.2, [max_px], fx_percent=fx, fy_percent=-fx / 2,
                    principal_px=0.3)


def test_spread_is_median_and_80th_percentile_of_magnitudes() -> None:
    median, high = spread([1.0, -2.0, 3.0, 4.0, -5.0])
    assert median == 3.0
    assert high == pytest.approx(4.2)
    assert spread([-0.5]) == (0.5, 0.5)


def test_table_has_a_row_per_measured_figure_and_counts_seeds() -> None:
    stereo = Accuracy(0.1, 0.0, 0.0, [0.2, 0.4], rotation_deg=-0.01, baseline_percent=0.03,
                      fx_percent=0.1, fy_percent=0.05, principal_px=0.2)
    results = {"heldout": {"camlog": [mono(0.01, 0.1), mono(-0.03, 0.3)],
                           "OpenCV": [mono(0.02, 0.5)]},
               "stereo": {"camlog": [stereo]}}
    lines = table(results, ["camlog", "OpenCV", "mrcal"], {("heldout", "OpenCV"): 1})
    text = "\n".join(lines)
    heldout = lines[2:lines.index(next(line for line in lines if line.startswith("stereo")))]
    assert heldout[0].split()[1:] == ["seeds", "n", "2", "n", "1,", "1", "failed", "-"]
    assert [row.split()[0] for row in heldout[1:]] == ["fx", "fy", "principal", "max"]
    max_row = next(row for row in heldout if "max projection" in row).split()
    assert max_row[3:] == ["0.2", "/", "0.26", "0.5", "/", "0.5", "-"]
    assert "rotation °" in text and "baseline %" in text
    assert text.count("rotation") == 1  # a mono case has no rig rows


def test_accuracy_reports_fx_fy_and_principal_point_distance() -> None:
    k = np.array([[500.0, 0.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]])
    truth = CameraModel(640, 480, k)
    off = k.copy()
    off[0, 0], off[1, 1], off[0, 2], off[1, 2] = 505.0, 510.0 * 0.98, 323.0, 244.0
    got = accuracy([CameraModel(640, 480, off)], [truth])
    assert got.fx_percent == pytest.approx(1.0)
    assert got.fy_percent == pytest.approx(-2.0)
    assert got.focal_percent == pytest.approx(-2.0)
    assert got.principal_px == pytest.approx(5.0)


def test_mrcal_answer_becomes_models_and_the_rig() -> None:
    truth = CameraModel(640, 480, np.diag([500.0, 500.0, 1.0]))
    cameras = [{"intrinsics": [501.0, 502.0, 321.0, 239.0, -0.1, 0.01, 0.0, 0.0, 0.002],
                "rt_cam_ref": [0.0] * 6},
               {"intrinsics": [499.0, 498.0, 318.0, 242.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                "rt_cam_ref": [0.0, 0.1, 0.0, -0.02, 0.0, 0.001]}]
    got = parse_answer({"cameras": cameras, "report": ["RMS 0.3"]}, [truth, truth])
    assert got.models[0].k[0, 0] == 501.0 and got.models[0].k[1, 2] == 239.0
    assert got.models[0].d.tolist() == [-0.1, 0.01, 0.0, 0.0, 0.002]
    assert got.right_from_left is not None
    rotation = got.right_from_left[:3, :3]
    assert np.degrees(np.arccos((np.trace(rotation) - 1) / 2)) == pytest.approx(
        np.degrees(0.1))
    assert got.right_from_left[:3, 3].tolist() == [-0.02, 0.0, 0.001]
    assert got.report == ["RMS 0.3"]
    with pytest.raises(MrcalError, match="did not converge"):
        parse_answer({"error": "did not converge"}, [truth])


def test_corners_cache_marks_unseen_points_and_numbers_frames_per_camera() -> None:
    text, globs = corners_vnl([{"frames": {"7": [[1.5, 2.0], None]}},
                               {"frames": {"7": [None, [3.0, 4.25]], "10000012": [None, None]}}])
    assert text.splitlines() == ["# filename x y level", "cam0-000007.png 1.5 2.0 0",
                                 "cam0-000007.png - - -", "cam1-000007.png - - -",
                                 "cam1-000007.png 3.0 4.25 0", "cam1-10000012.png - - -",
                                 "cam1-10000012.png - - -"]
    assert globs == ["cam0-*.png", "cam1-*.png"]


def test_mrcal_is_skipped_with_a_reason(tmp_path: Path) -> None:
    missing = mrcal_available(tmp_path / "python")
    assert missing is not None and "pip install" in missing
    without = mrcal_available(Path(sys.executable))
    if without is not None:  # this Python has no mrcal
        assert "cannot import mrcal" in without


def test_models_line_names_every_tools_lens_model() -> None:
    by_name = {c.name: c for c in CASES}
    assert "LENSMODEL_OPENCV5" in models_line(by_name["heldout"], mrcal=True)
    assert "LENSMODEL_OPENCV8" in models_line(by_name["charuco"], mrcal=True)
    assert "mrcal skipped" in models_line(by_name["heldout"], mrcal=False)
    assert "cv2.fisheye" in models_line(by_name["fisheye"], mrcal=True)


def test_default_flags_drop_only_the_whole_model_flags() -> None:
    by_name = {c.name: c.flags for c in CASES}
    assert default_flags(by_name["heldout"]) == "--camera /heldout_camera -s 7x6 -q 0.01"
    assert default_flags(by_name["charuco"]).endswith("--model rational_polynomial")
    assert default_flags(by_name["fisheye"]) == by_name["fisheye"]


def test_a_cached_recording_is_reused(tmp_path: Path) -> None:
    kept = tmp_path / "mono_heldout_3_10s.mcap"
    kept.write_bytes(b"kept")
    assert recording(CASES[0], 3, tmp_path, None) == kept
    assert kept.read_bytes() == b"kept"


def test_a_distorted_variant_of_a_scenario_has_its_own_recording(tmp_path: Path) -> None:
    by_name = {c.name: c for c in CASES}
    plain = tmp_path / "mono_moving_blur_2_10s.mcap"
    variant = tmp_path / "mono_moving_blur-moving_blur_k3_2_10s.mcap"
    plain.write_bytes(b"plain")
    variant.write_bytes(b"k3")
    assert recording(by_name["moving_blur"], 2, tmp_path, None) == plain
    assert recording(by_name["moving_blur_k3"], 2, tmp_path, None) == variant
    assert by_name["moving_blur_k3"].overrides["distortion"][4] != 0.0


def test_kept_seeds_are_read_back_and_a_cut_line_runs_again(tmp_path: Path) -> None:
    kept = tmp_path / "kept.jsonl"
    first = Progress(kept=kept)
    first.add("heldout", "camlog", mono(0.01, 0.1))
    first.fail("heldout", "OpenCV", 0, "no convergence")
    first.finish("heldout", 0)
    first.add("heldout", "camlog", mono(-0.03, 0.3))
    first.finish("heldout", 1)
    with kept.open("a", encoding="utf-8") as out:
        out.write('{"case": "heldout", "seed": 2, "resu')  # a run killed while writing
    again = Progress.resumed(kept)
    assert again.done == {("heldout", 0), ("heldout", 1)}
    assert again.results["heldout"]["camlog"] == [mono(0.01, 0.1), mono(-0.03, 0.3)]
    assert again.failures[("heldout", "OpenCV")] == ["seed 0: no convergence"]
    assert Progress.resumed(tmp_path / "absent.jsonl").done == set()


@pytest.mark.parametrize(("argv", "message"), [
    (["--cases", "heldout,nope"], "unknown cases nope"),
    (["--seeds", "0"], "--seeds must be at least 1"),
    (["--duration", "-1"], "--duration must be positive"),
])
def test_argument_errors_are_one_line(argv: list[str], message: str,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        parse_arguments(argv)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_defaults() -> None:
    args = parse_arguments([])
    assert args.seeds == 40
    assert args.cases.split(",") == ["heldout", "stereo", "charuco", "moving_blur",
                                     "moving_blur_k3", "fisheye"]
    assert args.keep is None
