"""camlog batch: parallel runs, failures, skipping, and the Ray engine."""

from __future__ import annotations

import json
import os
import socket
from pathlib import Path

import pytest

from camlog.batch.run import run_batch
from camlog.cli import main
from camlog.requests.batch import BatchRequest
from tests.slow import renders

SCENARIOS = Path(__file__).resolve().parents[3] / "datasets" / "scenarios"
PIPELINE = """
[[steps]]
run = "resync"

[[steps]]
run = "process"
topic = "/stereo_sync/left/image_raw"
edges = true

[[steps]]
run = "info"
"""


@pytest.fixture(scope="module")
@renders
def logs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    tmp = tmp_path_factory.mktemp("batch_logs")
    made = []
    for seed in (1, 2):
        path = tmp / f"cam{seed}.mcap"
        assert main(["record", str(SCENARIOS / "stereo_unsynced.toml"), "-o", str(path),
                     "--frames", "20", "--resolution", "160x120", "--seed", str(seed),
                     "--no-progress"]) == 0
        made.append(path)
    corrupt = tmp / "corrupt.mcap"
    corrupt.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 64)
    made.append(corrupt)
    return made


@pytest.fixture
def pipeline(tmp_path: Path) -> Path:
    path = tmp_path / "pipe.toml"
    path.write_text(PIPELINE)
    return path


def test_batch_survives_a_corrupt_log_and_reports_it(
    logs: list[Path], pipeline: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    code = main(["batch", str(pipeline), *map(str, logs), "-o", str(out), "-j", "2",
                 "--no-progress"])
    assert code == 1  # some failed
    table = capsys.readouterr().out
    assert "2 of 3 logs done (1 failed)" in table
    summary = json.loads((out / "batch_summary.json").read_text())
    status = {Path(s["log"]).name: s for s in summary["logs"]}
    assert status["corrupt.mcap"]["status"] == "failed"
    assert "corrupt.mcap" in status["corrupt.mcap"]["error"]
    for name in ("cam1.mcap", "cam2.mcap"):
        s = status[name]
        assert s["status"] == "ok"
        assert [step["name"] for step in s["steps"]] == ["resync", "process", "info"]
        assert s["steps"][0]["figures"]["pairs"] > 10
        assert s["steps"][1]["figures"]["frames"] == s["steps"][0]["figures"]["pairs"]
        info = Path(s["steps"][2]["files"][0]).read_text()
        assert "/stereo_sync/left/edges" in info and "/stereo_sync/left/image_raw" in info
    # per-log folders, one per step
    assert sorted(p.name for p in (out / "cam1").iterdir()) == [
        "01_resync", "02_process", "03_info", "batch_status.json"]


def test_rerun_skips_completed_logs_and_redoes_changed_ones(
    logs: list[Path], pipeline: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = logs[:2]
    out = tmp_path / "out"
    first = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(good), output=out, jobs=1,
                                         progress=True))
    assert [s["status"] for s in first.statuses] == ["ok", "ok"]
    bar = capsys.readouterr().err
    assert "running 1, queued 1, failed 0" in bar  # live counts beside the bar
    assert all(s["node"] and s["seconds"] > 0 for s in first.statuses)
    second = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(good), output=out, jobs=1,
                                          progress=False))
    assert [s["status"] for s in second.statuses] == ["skipped", "skipped"]
    # a changed pipeline redoes everything
    pipeline.write_text(PIPELINE.replace("edges = true", "edges = {low = 10, high = 30}"))
    third = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(good), output=out, jobs=1,
                                         progress=False))
    assert [s["status"] for s in third.statuses] == ["ok", "ok"]
    # a missing output redoes that log only
    Path(third.statuses[0]["steps"][1]["files"][0]).unlink()
    fourth = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(good), output=out, jobs=1,
                                          progress=False))
    assert [s["status"] for s in fourth.statuses] == ["ok", "skipped"]


#: the home of the user running the tests (read before conftest's temporary_home replaces
#: it), which they must leave as it is
REAL_HOME = Path(os.environ.get("HOME") or Path.home())


def listing(folder: Path) -> list[tuple[str, int, int]]:
    """Every file under ``folder``: name, size and modification time."""
    return sorted((str(p.relative_to(folder)), p.stat().st_size, p.stat().st_mtime_ns)
                  for p in folder.rglob("*")) if folder.exists() else []


def test_ray_engine_gives_the_same_results(logs: list[Path], pipeline: Path,
                                           tmp_path: Path, temporary_home: Path) -> None:
    """... and leaves the user's home alone: Ray's token for the local instance goes to
    the tests' temporary home."""
    import ray  # the test extra installs the optional 'ray' extra

    assert ray.__version__
    before = listing(REAL_HOME / ".ray")
    local = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(logs),
                                   output=tmp_path / "local", jobs=2, progress=False))
    ray_run = run_batch(BatchRequest(pipeline=pipeline, logs=tuple(logs), output=tmp_path / "ray",
                                     jobs=2, engine="ray", progress=False))
    assert listing(REAL_HOME / ".ray") == before
    assert Path.home() == temporary_home
    assert (temporary_home / ".ray" / "auth_token").is_file()
    assert any((temporary_home / "tmp" / "ray").glob("session_*"))
    assert [s["status"] for s in ray_run.statuses] == [s["status"] for s in local.statuses]
    for a, b in zip(local.statuses, ray_run.statuses, strict=True):
        assert [st["figures"] | {"fps": None} for st in a.get("steps", [])] == \
            [st["figures"] | {"fps": None} for st in b.get("steps", [])]


def test_bad_batch_arguments_are_one_line(
    logs: list[Path], pipeline: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[[steps]]\nrun = 'fly'\n")
    assert main(["batch", str(bad), str(logs[0]), "-o", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("camlog batch: error:") and "fly" in err[0]
    assert main(["batch", str(pipeline), str(logs[0]), "-o", str(tmp_path / "o"),
                 "-j", "0"]) == 1
    assert "--jobs must be at least 1" in capsys.readouterr().err


def test_an_unreachable_cluster_is_one_line(
    logs: list[Path], pipeline: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert main(["batch", str(pipeline), str(logs[0]), "-o", str(tmp_path / "o"), "--engine",
                 "ray", "--address", f"127.0.0.1:{port}", "--no-progress"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("camlog batch: error: cannot reach the Ray cluster at "
                             f"127.0.0.1:{port}")
