"""Golden-log regression: the processors over the committed golden inputs, against the
expected outputs (``pytest --update-goldens`` regenerates them instead of comparing).

The inputs are never re-recorded here (rendering differs across GL stacks); their sha256
is checked against the manifest first.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from camlog.cli import main
from camlog.errors import GoldenError
from camlog.golden import run as golden
from camlog.golden.artifacts import read_artifact
from camlog.golden.tolerances import TOLERANCES, tolerance_for
from processors import red_pixels
from processors.edges import Edges
from replay.messages import Image
from tests.slow import renders

GOLDEN = golden.golden_dir()
EXPECTED = GOLDEN / "expected"
RED = "red_block-seed0-640x480-f10"


@pytest.fixture(scope="module")
@renders
def artifacts(tmp_path_factory: pytest.TempPathFactory) -> golden.Artifacts:
    """Every golden output, computed once from the committed inputs (one camlog worker)."""
    assert golden.verify_inputs(GOLDEN) == []
    return golden.compute_outputs(GOLDEN, tmp_path_factory.mktemp("golden"), workers=1)


def skip_when_updating(update_goldens: bool) -> None:
    if update_goldens:
        pytest.skip("--update-goldens: regenerating, not comparing")


def test_manifest_records_every_input_and_its_checksum() -> None:
    manifest = json.loads((GOLDEN / "manifest.json").read_text())
    assert [e["file"] for e in manifest["inputs"]] == [g.file_name for g in golden.INPUTS]
    for entry, spec in zip(manifest["inputs"], golden.INPUTS, strict=True):
        assert entry["file"] == (f"{entry['scenario']}-seed{entry['seed']}-"
                                 f"{entry['options']['resolution']}-f{entry['options']['frames']}"
                                 ".mcap")
        assert entry["scenario"] == spec.scenario and entry["renderer"].startswith("mujoco/")
        assert entry["mujoco_version"] and entry["camlog_version"]
        assert entry["size_bytes"] < 4_000_000 and len(entry["sha256"]) == 64
    assert golden.verify_inputs(GOLDEN) == []


def test_outputs_match_expected(artifacts: golden.Artifacts, update_goldens: bool,
                                tmp_path: Path) -> None:
    if update_goldens:
        print("\n".join(golden.update(EXPECTED, artifacts)))
        return
    differences = golden.compare(EXPECTED, artifacts, tmp_path / "diff")
    assert not differences, "golden outputs differ (camlog golden update, or pytest " \
        "--update-goldens, after review):\n" + "\n".join(
            f"{d}\n{d.detail}" if d.detail else str(d) for d in differences)


def test_outputs_do_not_depend_on_workers(artifacts: golden.Artifacts, tmp_path: Path) -> None:
    """Bit-identical artifacts with two camlog workers per job (and so on a second run)."""
    again = golden.compute_outputs(GOLDEN, tmp_path, workers=2)
    assert golden.artifacts_equal(artifacts, again) == []


@pytest.mark.slow
def test_a_one_pixel_centroid_shift_fails_with_the_numbers(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, update_goldens: bool) -> None:
    skip_when_updating(update_goldens)
    original = red_pixels.mask_centroid

    def shifted(mask: np.ndarray) -> tuple[float, float, int]:
        u, v, count = original(mask)
        return u + 1.0, v, count

    monkeypatch.setattr(red_pixels, "mask_centroid", shifted)
    differences = golden.check(GOLDEN, EXPECTED, diff_dir=tmp_path / "diff", only=[RED])
    lines = [str(d) for d in differences]
    assert f"{RED}/left/red_centroid.json: frames[0].u_px: expected 319.5, got 320.5 " \
        "(|diff| 1 > abs 1e-06 px)" in lines
    # the right camera's marker square moves one pixel (u 109.8 -> 110.8): its mask video
    # fails by RMS, with images; the left one does not, as round(319.5) == round(320.5)
    videos = {d.artifact.removeprefix(f"{RED}/"): d for d in differences if ".png" in d.artifact}
    assert sorted(videos) == ["right/output_video-first.png", "right/output_video-last.png"]
    what = videos["right/output_video-first.png"].what
    assert what.startswith("RMS ") and "> 0.5" in what and "pixels differ" in what
    for kind in ("expected", "actual", "difference"):
        assert (tmp_path / "diff" / RED / "right" / f"output_video-first.{kind}.png").is_file()
    assert not any("edges" in d.artifact for d in differences)

    monkeypatch.undo()
    assert golden.check(GOLDEN, EXPECTED, diff_dir=tmp_path / "after", only=[RED]) == []
    assert not (tmp_path / "after").exists()


@pytest.mark.slow
def test_edges_shifted_by_one_pixel_fail_by_rms(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path, update_goldens: bool) -> None:
    skip_when_updating(update_goldens)
    original = Edges.__call__

    def shifted(self: Edges, image: Image) -> list[tuple[str, object]]:
        ((topic, edges),) = original(self, image)
        assert isinstance(edges, Image)
        return [(topic, dataclasses.replace(edges, pixels=np.roll(edges.pixels, 1, axis=1)))]

    monkeypatch.setattr(Edges, "__call__", shifted)
    differences = golden.check(GOLDEN, EXPECTED, diff_dir=tmp_path, only=[RED])
    names = sorted(d.artifact for d in differences)
    assert names == [f"{RED}/{side}/edges-{which}.png" for side in ("left", "right")
                     for which in ("first", "last")]  # the same edge count: only images see it
    worst = differences[0].what
    rms = float(worst.split()[1])
    assert worst.startswith("RMS ") and rms > 10 * tolerance_for(names[0]).abs
    difference = read_artifact(tmp_path / RED / "left" / "edges-first.difference.png")
    assert difference.shape == (480, 640) and difference.max() == 255

    monkeypatch.undo()
    assert golden.check(GOLDEN, EXPECTED, diff_dir=tmp_path / "after", only=[RED]) == []


def test_numbers_compare_within_their_tolerance(tmp_path: Path) -> None:
    name = f"{RED}/left/red_centroid.json"
    expected = read_artifact(EXPECTED / name)
    near = json.loads(json.dumps(expected))
    near["frames"][3]["u_px"] += 5e-7  # inside abs 1e-6 px
    missing = golden.compare(EXPECTED, {name: near})  # the rest of red_block is missing
    assert len(missing) == 13 and all("has no computed artifact" in d.what for d in missing)
    only_this = {n: read_artifact(EXPECTED / n) for n in _expected_files(RED)} | {name: near}
    assert golden.compare(EXPECTED, only_this) == []
    far = json.loads(json.dumps(expected))
    far["frames"][3]["count"] += 1
    far["frames"][4]["v_px"] = None
    lines = [str(d) for d in golden.compare(EXPECTED, only_this | {name: far})]
    assert lines == [f"{name}: frames[3].count: expected 46656, got 46657 (|diff| 1 > exact)",
                     f"{name}: frames[4].v_px: expected 239.5, got null"]


def test_text_differences_come_with_a_unified_diff() -> None:
    name = f"{RED}/left/output.txt"
    actual = {n: read_artifact(EXPECTED / n) for n in _expected_files(RED)}
    actual[name] = actual[name].replace("/stereo_camera/left/edges  sensor_msgs/msg/Image  10",
                                        "/stereo_camera/left/edges  sensor_msgs/msg/Image  9")
    (difference,) = golden.compare(EXPECTED, actual)
    assert str(difference) == f"{name}: text differs (2 lines added or removed)"
    assert "-/stereo_camera/left/edges  sensor_msgs/msg/Image  10" in difference.detail
    assert "+/stereo_camera/left/edges  sensor_msgs/msg/Image  9" in difference.detail


def test_update_rewrites_only_what_changed(tmp_path: Path) -> None:
    expected = tmp_path / "expected"
    shutil.copytree(EXPECTED / RED, expected / RED)
    actual = {n: read_artifact(EXPECTED / n) for n in _expected_files(RED)}
    centroid = f"{RED}/left/red_centroid.json"
    actual[centroid]["frames"][0]["u_px"] = 319.5 + 2e-7  # noise: kept as it was
    actual[f"{RED}/right/red_centroid.json"]["frames"][0]["u_px"] = 110.0
    del actual[f"{RED}/left/edges-last.png"]
    actual[f"{RED}/left/new.txt"] = "new\n"
    lines = golden.update(expected, actual)
    assert lines[0] == f"added    {RED}/left/new.txt"
    assert lines[1] == f"changed  {RED}/right/red_centroid.json"
    assert lines[2].strip().startswith("frames[0].u_px: expected 109.79725475380934, got 110.0")
    assert f"removed  {RED}/left/edges-last.png" in lines
    assert lines[-1] == "unchanged 12 files (equal within tolerance)"
    assert read_artifact(expected / centroid)["frames"][0]["u_px"] == 319.5
    assert golden.compare(expected, actual) == []


def test_a_changed_input_byte_is_refused(tmp_path: Path) -> None:
    spec = next(g for g in golden.INPUTS if g.stem == RED)
    shutil.copy(GOLDEN / "manifest.json", tmp_path)
    data = bytearray((GOLDEN / spec.file_name).read_bytes())
    data[len(data) // 2] ^= 1
    (tmp_path / spec.file_name).write_bytes(bytes(data))
    (problem,) = golden.verify_inputs(tmp_path, only=[RED])
    assert problem == f"{tmp_path / spec.file_name}: sha256 differs from manifest.json " \
        "(re-recorded by hand? use camlog golden record)"
    with pytest.raises(GoldenError, match="sha256 differs"):
        golden.compute_outputs(tmp_path, tmp_path / "work", only=[RED])


@pytest.mark.slow
def test_record_writes_the_input_and_its_manifest_entry(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    tiny = golden.GoldenInput("red_block", seed=3, width=64, height=48, frames=2)
    monkeypatch.setattr(golden, "INPUTS", (tiny,))
    (line,) = golden.record_inputs(tmp_path)
    assert line.startswith("new       red_block-seed3-64x48-f2.mcap (")
    (entry,) = json.loads((tmp_path / "manifest.json").read_text())["inputs"]
    assert entry["file"] == "red_block-seed3-64x48-f2.mcap"
    assert entry["options"] == {"frames": 2, "resolution": "64x48"}
    assert entry["size_bytes"] == (tmp_path / entry["file"]).stat().st_size
    assert golden.verify_inputs(tmp_path) == []


@pytest.mark.slow
def test_cli_check(capsys: pytest.CaptureFixture[str], update_goldens: bool) -> None:
    skip_when_updating(update_goldens)
    assert main(["golden", "check", "--only", "red_block", "--workers", "2"]) == 0
    assert capsys.readouterr().out.startswith("golden outputs match ")
    assert main(["golden", "check", "--only", "nonesuch"]) == 1
    assert "camlog golden: error: unknown golden input nonesuch" in capsys.readouterr().err


def test_every_tolerance_says_why() -> None:
    assert all(t.why and (t.abs >= 0 and t.rel >= 0) for t in TOLERANCES)
    assert TOLERANCES[-1].pattern == "*" and TOLERANCES[-1].describe() == "exact"
    assert tolerance_for("x/calibrate/calibration.json:cameras[1].parameters.cx.value").abs \
        == 0.03
    assert tolerance_for("x/calibrate/left.yaml:projection_matrix.data[2]").abs == 0.2


def _expected_files(stem: str) -> list[str]:
    return sorted(p.relative_to(EXPECTED).as_posix() for p in (EXPECTED / stem).rglob("*")
                  if p.is_file())
