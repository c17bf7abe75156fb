"""``camlog calibrate`` accepts ROS camera_calibration's spellings and says so in --help."""

from __future__ import annotations

import contextlib
import io

import pytest

from camlog.cli import build_parser

LONG = ["calibrate", "run.mcap", "--size", "8x6", "--square", "0.108", "--pattern",
        "chessboard", "--camera-name", "narrow_stereo", "--k-coefficients", "3"]
# as typed by someone coming from `ros2 run camera_calibration cameracalibrator`
ROS = ["calibrate", "run.mcap", "-s", "8x6", "-q", "0.108", "-p", "chessboard",
       "--camera_name", "narrow_stereo", "-k", "3"]


@pytest.mark.parametrize("argv", [ROS, [*ROS[:8], "-c", "narrow_stereo", "-k", "3"]])
def test_camera_calibration_spellings_mean_the_same(argv: list[str]) -> None:
    parser = build_parser(["calibrate"])
    long = vars(parser.parse_args(LONG))
    ros = vars(parser.parse_args(argv))
    assert ros == long
    assert (ros["size"], ros["square"], ros["camera_name"]) == ("8x6", 0.108, "narrow_stereo")


def test_help_names_the_aliases() -> None:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        build_parser(["calibrate"]).parse_args(["calibrate", "--help"])
    text = " ".join(out.getvalue().split())
    assert "camera_calibration's spellings are accepted" in text
    for spelling in ("-s/--size", "-q/--square", "-c/--camera_name", "--fix-principal-point"):
        assert spelling in text
