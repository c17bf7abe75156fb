"""The calibration corpus: its manifest always, the OpenCV reference when the cache holds data."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmarks.corpus.manifest import (
    LICENCES,
    CorpusError,
    default_cache,
    load_manifest,
)
from benchmarks.corpus.reference import reference_calibration
from benchmarks.corpus.run import camlog_args, camlog_calibration
from camlog.cli import main

SMALL = "boofcv_sony_chess"


def cached(name: str) -> Path:
    folder = default_cache() / name
    if not folder.is_dir():
        pytest.skip(f"corpus cache {folder} absent: run python -m benchmarks.corpus.fetch "
                    "(--mirror-root DIR: local clones, without network)")
    return folder


def test_every_entry_has_provenance_licence_and_board() -> None:
    datasets = load_manifest()
    assert len(datasets) >= 10
    for dataset in datasets:
        assert dataset.licence in LICENCES and dataset.licence_source
        assert dataset.board.square_m > 0 and dataset.board.note
        assert dataset.files
    kinds = {(d.model, d.stereo, d.board.pattern) for d in datasets}
    assert {m for m, _s, _p in kinds} >= {"plumb_bob", "equidistant"}
    assert {s for _m, s, _p in kinds} == {False, True}
    assert {p for _m, _s, p in kinds} >= {"chessboard", "circles", "charuco"}


def test_a_broken_entry_names_its_field(tmp_path: Path) -> None:
    text = Path("benchmarks/corpus/manifest.toml").read_text()
    broken = tmp_path / "manifest.toml"
    broken.write_text(text.replace('licence = "CC-BY-4.0"', 'licence = "GPL-9"', 1))
    with pytest.raises(CorpusError, match="licence 'GPL-9'"):
        load_manifest(broken)


def test_camlog_options_follow_the_board() -> None:
    circles = next(d for d in load_manifest() if d.board.pattern == "circles")
    args = camlog_args(circles)
    assert args[:6] == ["--size", "8x10", "--square", "0.025", "--pattern", "circles"]
    assert "--diameter" in args and args[-2:] == ["--camera", "/corpus"]
    charuco = next(d for d in load_manifest() if d.board.pattern == "charuco")
    args = camlog_args(charuco)
    assert args[:6] == ["--size", "5x10", "--square", "0.055", "--pattern", "charuco"]
    assert args[args.index("--marker") + 1] == "0.043"
    assert args[args.index("--dictionary") + 1] == "DICT_4X4_50"
    assert "--legacy-pattern" in args


def test_opencv_reference_on_a_small_dataset() -> None:
    dataset = next(d for d in load_manifest() if d.name == SMALL)
    folder = cached(SMALL)
    result = reference_calibration(dataset, folder)
    (camera,) = result.cameras
    assert camera.views == 13
    assert camera.rms_px < 0.3
    assert dataset.reference is not None
    assert abs(camera.fx - dataset.reference.fx) / dataset.reference.fx < 0.02
    assert abs(camera.cx - dataset.reference.cx) < 5


def test_fisheye_photos_calibrate_at_any_import_rate(tmp_path: Path) -> None:
    # 15 hand-held photos through a fisheye: OpenCV's fast chessboard check finds the board
    # in 4, the sector-based detector in 14; a folder of photos is searched with every
    # detector whatever the rate it was imported at (10 Hz by default)
    folder = cached("ocamcalib_fisheye1")
    log = tmp_path / "fisheye.mcap"
    assert main(["import", str(folder), "-o", str(log), "--camera", "/fisheye"]) == 0
    out = tmp_path / "cal"
    assert main(["calibrate", str(log), "--camera", "/fisheye", "--size", "8x6", "--square",
                 "0.0325", "--model", "equidistant", "-o", str(out), "--no-progress",
                 "--no-report"]) == 0
    (camera,) = json.loads((out / "calibration.json").read_text())["cameras"]
    assert camera["boards_found"] == 15
    assert camera["used_views"] >= 14
    assert camera["rms_px"] < 0.5


def test_a_legacy_charuco_board_calibrates_as_well_as_opencv(tmp_path: Path) -> None:
    # 13 photos of a 5x10-square board printed in OpenCV's layout before 4.6 (an even number
    # of rows moves its markers): every photo gives its 36 corners to both
    dataset = next(d for d in load_manifest() if d.name == "mono3d_charuco")
    folder = cached(dataset.name)
    (opencv,) = reference_calibration(dataset, folder).cameras
    (camera,) = camlog_calibration(dataset, folder, tmp_path).cameras
    assert opencv.views == camera.views == 13
    assert camera.rms_px <= opencv.rms_px
    assert abs(camera.fx - opencv.fx) / opencv.fx < 0.01
