"""``camlog check``: a drifted stereo log is flagged from the drift on, a clean one is not;
its exit status says which; its rerun recording holds what its report shows."""

from __future__ import annotations

import csv
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np
import pytest

from camlog.check.flow import EXIT_DRIFTED, EXIT_NOT_JUDGED, CheckOptions, check_drift
from camlog.check.recording import TIMELINE
from camlog.cli import main
from processors.calibration.board import make_board
from tests.rrd import load_rrd, rerun_cli

DRIFT_S, DRIFT_DEG = 3.0, 0.1
RIGHT = "/stereo_camera/right"


def _record(path: Path, *args: str) -> Path:
    assert main(["record", *args, "--resolution", "320x240", "-o", str(path),
                 "--no-progress"]) == 0
    return path


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """stereo_checkerboard, 6 s at 320x240: seed 0 with the right camera pitched 0.1° from
    3 s on, and a clean seed 1; mono_checkerboard, 2 s."""
    folder = tmp_path_factory.mktemp("check")
    return {
        "drifted": _record(folder / "drifted.mcap", "stereo_checkerboard", "--duration", "6",
                           "--drift", f"right:pitch:{DRIFT_DEG}@{DRIFT_S}"),
        "clean": _record(folder / "clean.mcap", "stereo_checkerboard", "--duration", "6",
                         "--seed", "1"),
        "mono": _record(folder / "mono.mcap", "mono_checkerboard", "--duration", "2"),
    }


@pytest.fixture(scope="module")
def report(logs: dict[str, Path], tmp_path_factory: pytest.TempPathFactory
           ) -> tuple[Path, list[str]]:
    """``camlog check`` of the drifted and the clean log, 1 s windows: folder and stdout."""
    out = tmp_path_factory.mktemp("report") / "check"
    printed = StringIO()
    with redirect_stdout(printed):
        assert main(["check", str(logs["drifted"]), str(logs["clean"]), "--window", "1",
                     "-o", str(out)]) == EXIT_DRIFTED
    return out, printed.getvalue().splitlines()


def _rows(folder: Path, log: Path, metric: str) -> list[dict[str, str]]:
    with (folder / "check.csv").open() as f:
        return [r for r in csv.DictReader(f) if r["log"] == str(log) and r["metric"] == metric]


def test_the_drifted_log_is_flagged_from_the_drift_on_and_not_before(
        report: tuple[Path, list[str]], logs: dict[str, Path]) -> None:
    rows = _rows(report[0], logs["drifted"], "vertical_error_px")
    assert len(rows) == 6
    assert all(r["camera"] == RIGHT for r in rows)
    flagged = [float(r["start_s"]) for r in rows if r["flagged"] == "1"]
    assert flagged == [3.0, 4.0, 5.0]


def test_the_estimated_rotation_is_the_drift(report: tuple[Path, list[str]],
                                             logs: dict[str, Path]) -> None:
    rotation = [float(r["value"]) for r in _rows(report[0], logs["drifted"], "rotation_deg")
                if r["flagged"] == "1"]
    pitch = [float(r["value"]) for r in _rows(report[0], logs["drifted"], "pitch_deg")
             if r["flagged"] == "1"]
    assert np.median(rotation) == pytest.approx(DRIFT_DEG, rel=0.25)
    assert np.median(pitch) == pytest.approx(DRIFT_DEG, rel=0.25)


def test_the_clean_log_has_no_flagged_window(report: tuple[Path, list[str]],
                                             logs: dict[str, Path]) -> None:
    rows = _rows(report[0], logs["clean"], "vertical_error_px")
    assert len(rows) == 6
    assert not any(r["flagged"] == "1" for r in rows)


def test_one_line_per_log_and_the_report(report: tuple[Path, list[str]],
                                         logs: dict[str, Path]) -> None:
    folder, lines = report
    assert lines[0].startswith(f"{logs['drifted']}: drifted: {RIGHT} from 3 s, rotated 0.")
    assert lines[1].startswith(f"{logs['clean']}: clean")
    text = (folder / "report.md").read_text()
    for name in ("drifted_mcap_check.png", "clean_mcap_check.png"):
        assert f"![{name}]({name})" in text
        assert (folder / name).read_bytes()[:4] == b"\x89PNG"


def test_a_mono_camera_without_a_board_is_not_checkable(logs: dict[str, Path]) -> None:
    checked = check_drift(logs["mono"], CheckOptions())
    assert checked.series == []
    assert "/simple_camera: a mono camera: no stereo partner and no board" in checked.summary()
    assert checked.summary().startswith(f"{logs['mono']}: not judged: nothing checkable")


def test_a_camera_that_sees_the_board_is_checked_by_its_reprojection(
        logs: dict[str, Path]) -> None:
    checked = check_drift(logs["mono"], CheckOptions(window_s=0.5,
                                                   board=make_board("7x6", 0.01)))
    (series,) = checked.series
    assert series.metric == "reprojection_px"
    assert all(0 < v < 0.3 for v in series.values["reprojection_px"])
    assert not any(series.flagged)
    assert "clean" in checked.summary()


def test_a_threshold_overrides_the_limit(logs: dict[str, Path]) -> None:
    checked = check_drift(logs["clean"], CheckOptions(window_s=3.0, threshold=1e-6))
    assert checked.series[0].limit == 1e-6
    assert all(checked.series[0].flagged)


@pytest.mark.parametrize(("args", "needle"), [
    (["--size", "7x6"], "a board needs both --size and --square"),
    (["--calibration", "/nonexistent/ost.yaml"], "ost.yaml"),
    (["--camera", "/nowhere"], "no images under camera /nowhere"),
])
def test_errors_are_one_line(logs: dict[str, Path], capsys: pytest.CaptureFixture[str],
                             tmp_path: Path, args: list[str], needle: str) -> None:
    code = main(["check", str(logs["mono"]), "-o", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 1
    assert len(err.splitlines()) == 1 and err.startswith("camlog check: error: ")
    assert needle in err


def test_a_batch_pipeline_checks_every_log(logs: dict[str, Path], tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    pipeline = tmp_path / "check.toml"
    pipeline.write_text('[[steps]]\nrun = "check"\nwindow = 1.0\n')
    out = tmp_path / "batch"
    assert main(["batch", str(pipeline), str(logs["drifted"]), str(logs["clean"]), "-j", "1",
                 "-o", str(out), "--no-progress"]) == 0
    table = capsys.readouterr().out
    assert "flagged_windows" in table or "drifted_from_s" in table
    found = {}
    for path in out.rglob("check.csv"):
        with path.open() as f:
            rows = [r for r in csv.DictReader(f) if r["metric"] == "vertical_error_px"]
        found[Path(rows[0]["log"]).name] = [float(r["start_s"]) for r in rows
                                            if r["flagged"] == "1"]
    assert found == {"drifted.mcap": [3.0, 4.0, 5.0], "clean.mcap": []}


def test_too_few_windows_to_measure_the_noise_are_not_judged(logs: dict[str, Path]) -> None:
    checked = check_drift(logs["drifted"], CheckOptions(window_s=3.0))
    assert checked.windows == 2
    assert not any(checked.series[0].flagged)
    assert "not judged" in checked.summary()


def test_a_log_without_a_usable_window_is_not_judged(logs: dict[str, Path]) -> None:
    checked = check_drift(logs["mono"], CheckOptions(window_s=0.5,
                                                   board=make_board("4x3", 0.01)))
    assert checked.verdict == "not judged"
    assert checked.summary().endswith(
        "not judged (/simple_camera: the board was not found in any window)")


def _check(tmp_path: Path, *logs: Path) -> tuple[int, list[str]]:
    printed = StringIO()
    with redirect_stdout(printed):
        code = main(["check", *map(str, logs), "--window", "1", "-o", str(tmp_path / "out")])
    return code, printed.getvalue().splitlines()


def test_exit_status_0_when_every_log_is_clean(logs: dict[str, Path], tmp_path: Path) -> None:
    code, lines = _check(tmp_path, logs["clean"])
    assert code == 0
    assert lines[0].startswith(f"{logs['clean']}: clean")


def test_exit_status_4_when_a_log_is_not_judged(logs: dict[str, Path], tmp_path: Path
                                                ) -> None:
    code, lines = _check(tmp_path, logs["clean"], logs["mono"])
    assert code == EXIT_NOT_JUDGED == 4
    assert lines[1] == (f"{logs['mono']}: not judged: nothing checkable (/simple_camera: a "
                        "mono camera: no stereo partner and no board given (--size/--square))")


def test_exit_status_3_when_a_log_drifted_whatever_the_others(
        logs: dict[str, Path], tmp_path: Path) -> None:
    code, _ = _check(tmp_path, logs["mono"], logs["drifted"])
    assert code == EXIT_DRIFTED == 3


def test_exit_status_2_for_a_usage_error(logs: dict[str, Path], tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["check", str(logs["clean"]), "--window", "0", "-o", str(tmp_path / "out")])
    assert exited.value.code == 2
    assert len(capsys.readouterr().err.splitlines()) == 1


def test_the_rerun_recording_holds_the_check(report: tuple[Path, list[str]],
                                             logs: dict[str, Path], tmp_path: Path) -> None:
    path = report[0] / "check.rrd"
    verified = rerun_cli("rrd", "verify", str(path), cwd=tmp_path)
    assert verified.returncode == 0, verified.stderr
    recording = load_rrd(path)
    assert recording.blueprints == 1
    drifted = f"/drifted.mcap{RIGHT}"
    metric = recording.column(f"{drifted}/drift_sigmas", "Scalars:scalars")
    assert len(metric) == 6
    assert recording.time(f"{drifted}/drift_sigmas", TIMELINE) == [
        int((t + 0.5) * 1e9) for t in range(6)]
    rows = _rows(report[0], logs["drifted"], "drift_sigmas")
    assert [v[0] for v in metric] == pytest.approx([float(r["value"]) for r in rows],
                                                   rel=1e-5)
    assert {v[0] for v in recording.column(f"{drifted}/limit", "Scalars:scalars")} == {5.0}
    # the flags as a step: each window's start and end
    flags = [v[0] for v in recording.column(f"{drifted}/flagged", "Scalars:scalars")]
    assert flags == [0.0] * 6 + [1.0] * 6
    assert recording.time(f"{drifted}/flagged", TIMELINE)[:2] == [0, int(1e9)]
    (verdict,) = recording.column("/drifted.mcap/verdict", "TextLog:text")
    assert verdict == [report[1][0]]
    clean = recording.column(f"/clean.mcap{RIGHT}/flagged", "Scalars:scalars")
    assert [v[0] for v in clean] == [0.0] * 12
