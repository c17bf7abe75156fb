"""Bad arguments: one line on stderr naming what is wrong, a non-zero exit, nothing written.

Each case is refused before any work starts (argument types check finite, positive,
non-empty and sane values), so these run in-process and fast.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from camlog.cli import main

LONG = "x" * 240  # with camlog's temporary name, more than a file name may have
LEFT = "/stereo_camera/left/image_raw"

#: (arguments, words the error line must contain); LOG is a small log, DIR an image folder
CASES = [
    (["record", "red_block", "--frames", "1e11"], "--frames: expected an integer"),
    (["record", "red_block", "--frames", "100000000000"], "--frames: expected 1..1000000"),
    (["record", "red_block", "--frames", "0"], "--frames: expected 1..1000000"),
    (["record", "red_block", "--duration", "nan"], "--duration: expected a finite number"),
    (["record", "red_block", "--duration", "-1"], "--duration: expected a number > 0"),
    (["record", "red_block", "--duration", "1e9"], "--duration: expected a number <= 86400"),
    (["record", "red_block", "--resolution", "100000x100000"],
     "resolution 100000x100000 is too large"),
    (["record", "red_block", "--resolution", "0x0"], "resolution 0x0 is too small"),
    (["record", "red_block", "--hfov", "nan"], "--hfov: expected a finite number"),
    (["record", "red_block", "--noise", "-1"], "--noise: expected a number >= 0"),
    (["record", "red_block", "--intrinsics", "nan,1,1,1"], "expected finite numbers"),
    (["record", "red_block", "--distortion", "plumb_bob:1,2"], "plumb_bob has 5 coefficients"),
    (["record", "red_block", "--seed", "-1"], "--seed: expected 0.."),
    (["record", "red_block", "-o", f"{LONG}.mcap"], "bytes long; file systems allow 255"),
    (["record", "red_block", "--compression", "zstd", "-o", "x.bag", "--frames", "1"],
     "ROS1 bags cannot use 'zstd'"),
    (["resync", "LOG", "-o", "r.mcap", "--slop", "nan"], "--slop: expected a finite number"),
    (["resync", "LOG", "-o", "r.mcap", "--slop", "inf"], "--slop: expected a finite number"),
    (["resync", "LOG", "-o", "r.mcap", "--slop", "-1"], "--slop: expected a number >= 0"),
    (["resync", "LOG", "-o", "r.mcap", "--left", ""], "--left: expected a name"),
    (["process", "LOG", "--topic", LEFT, "--edges", "--max-frames", "-1", "-o", "p.mcap"],
     "--max-frames: expected >= 1"),
    (["process", "LOG", "--topic", LEFT, "--edges", "--max-frames", "0", "-o", "p.mcap"],
     "--max-frames: expected >= 1"),
    (["process", "LOG", "--topic", LEFT, "--edges", "--workers", "0", "-o", "p.mcap"],
     "--workers: expected 1..256"),
    (["process", "LOG", "--topic", LEFT, "--edges", "--rate", "nan", "-o", "p.mcap"],
     "--rate: expected a finite number"),
    (["process", "LOG", "--topic", "", "--edges", "-o", "p.mcap"], "--topic: expected a name"),
    (["process", "LOG", "--topic", "/a b", "--edges", "-o", "p.mcap"], "has spaces"),
    (["process", "LOG", "--topic", LEFT, "--edges", "--low", "nan", "-o", "p.mcap"],
     "--low: expected a finite number"),
    (["calibrate", "LOG", "--size", "7x6", "--square", "nan"], "--square: expected a finite"),
    (["calibrate", "LOG", "--size", "7x6", "--square", "0.01", "--approximate", "nan"],
     "--approximate: expected a finite"),
    (["calibrate", "LOG", "--size", "7x6", "--square", "0.01", "--camera", ""],
     "--camera: expected a name"),
    (["calibrate", "LOG", "-s", "4x11", "-q", "0.01", "-p", "acircles", "--diameter", "nan"],
     "--diameter: expected a finite"),
    (["calibrate", "LOG", "-s", "4x11", "-q", "0.01", "-p", "acircles", "--diameter", "0"],
     "--diameter: expected a number > 0"),
    (["calibrate", "LOG", "--size", "7x6", "--square", "0.01", "--diameter", "0.005"],
     "--diameter belongs to circle grids"),
    (["calibrate", "LOG", "-s", "4x11", "-q", "0.01", "-p", "acircles", "--diameter", "0.015"],
     "circles 0.015 m across would overlap"),
    (["view", "LOG", "-o", "v.rrd", "--residual-scale", "nan"], "--residual-scale"),
    (["view", "LOG", "-o", "v.rrd", "--start", "inf"], "--start: expected a finite number"),
    (["view", "LOG", "-o", "v.rrd", "--every", "0"], "--every: expected >= 1"),
    (["view", "LOG", "-o", f"{LONG}.rrd"], "bytes long"),
    (["play", "LOG", "--rate", "nan", "-o", "p.mcap"], "--rate: expected a finite number"),
    (["play", "LOG", "--rate", "1e-300", "-o", "p.mcap"], "--rate: expected a number >= 0.001"),
    (["convert", "LOG", f"{LONG}.mcap"], "bytes long"),
    (["convert", "LOG", "c.mcap", "--end", "-1"], "--end: expected a number >= 0"),
    (["import", "DIR", "-o", "i.mcap", "--topic", ""], "--topic: expected a name"),
    (["import", "DIR", "-o", "i.mcap", "--rate", "nan"], "--rate: expected a finite number"),
    (["import", "DIR", "-o", "i.mcap", "--rate", "0"], "--rate: expected a number > 0"),
    (["demo", "--duration", "nan"], "--duration: expected a finite number"),
    (["golden", "check", "--workers", "0"], "--workers: expected 1..64"),
]


@pytest.fixture
def inputs(tmp_path: Path, red_log: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    """What LOG and DIR stand for (a small log, a folder with one image); the test runs in
    an empty folder, WORK."""
    import cv2
    import numpy as np

    folder = tmp_path / "images"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.png"), np.zeros((20, 30, 3), np.uint8))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    return {"LOG": str(red_log), "DIR": str(folder), "WORK": str(work)}


@pytest.mark.parametrize(("argv", "words"), CASES, ids=[" ".join(c[0])[:60] for c in CASES])
def test_bad_argument_is_one_line_and_writes_nothing(
    capsys: pytest.CaptureFixture[str], inputs: dict[str, str], argv: list[str], words: str,
) -> None:
    args = [inputs.get(a, a) for a in argv]
    try:
        code = main(args)
    except SystemExit as exit_:  # argparse refuses with status 2
        code = int(exit_.code or 0)
    out, err = capsys.readouterr()
    assert code != 0
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"camlog {argv[0]}: error: "), lines[0]
    assert words in lines[0], lines[0]
    assert "Traceback" not in err and out == ""
    assert list(Path(inputs["WORK"]).iterdir()) == []


NESTED = "must be a value, a list of values or a table of values"


@pytest.mark.parametrize(("text", "words"), [
    ('steps = [{run = {a = 1}}]', "unknown step {'a': 1}"),
    ('steps = [{run = "process", topic = {a = [1]}, edges = true}]', f"topic {NESTED}"),
    ('steps = [{run = "process", topic = "/a", edges = {low = {x = 1}}}]', f"edges {NESTED}"),
    ('steps = [{run = "resync", slop = nan}]', f"slop {NESTED}"),
    ('steps = [{run = "resync", slop = [1, [2]]}]', f"slop {NESTED}"),
    ('steps = [{run = "info", name = [1]}]', "name must be a non-empty text"),
    # a list that holds itself: nested without end
    ("steps:\n  - run: process\n    topic: &a [*a]\n", "more than 64 levels deep"),
    ("steps:\n  - run: process\n    topic: /x\n    edges: {low: [1, {a: .nan}]}\n",
     f"edges {NESTED}"),
])
def test_nested_pipeline_values_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], red_log: Path, text: str, words: str
) -> None:
    pipeline = tmp_path / ("p.yaml" if text.startswith("steps:") else "p.toml")
    pipeline.write_text(text)
    code = main(["batch", str(pipeline), str(red_log), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 1
    assert err.splitlines() == [err.strip()] and words in err, err
    assert not (tmp_path / "out").exists()
