"""The process engine under faults: a worker killed mid-log, the batch process killed."""

from __future__ import annotations

import json
import os
import signal
from pathlib import Path

import pytest

from camlog.batch.run import run_batch
from camlog.requests.batch import BatchRequest

from .faults import (
    alive,
    kill_when,
    output_files,
    pool_workers,
    start_batch,
    wait_for,
)


@pytest.fixture
def fault_logs(short_logs: list[Path]) -> list[Path]:
    """Three of the short logs."""
    return short_logs[:3]


@pytest.mark.slow
def test_a_killed_worker_is_retried_and_outputs_are_complete(fault_logs: list[Path],
                                                             tmp_path: Path) -> None:
    pipeline_file = fault_logs[0].parent / "pipe.toml"
    reference = tmp_path / "reference"
    clean = run_batch(BatchRequest(pipeline=pipeline_file, logs=tuple(fault_logs),
                                   output=reference, jobs=2, progress=False))
    assert not clean.failed
    out = tmp_path / "out"
    batch = start_batch([str(pipeline_file), *map(str, fault_logs), "-o", str(out), "-j", "2"])

    def busy_worker() -> int | None:
        # a log has started (a step folder is there) and is not complete (no status)
        folders = [d for d in out.iterdir() if d.is_dir()] if out.exists() else []
        started = any(any(d.glob("01_*")) and not (d / "batch_status.json").exists()
                      for d in folders)
        workers = pool_workers(batch.pid)
        return workers[0] if started and len(workers) == 2 else None

    kill_when(busy_worker, 120, "a log in progress")
    stdout, stderr = batch.communicate(timeout=300)
    assert batch.returncode == 0, stderr
    assert "3 of 3 logs done (0 failed)" in stdout
    summary = json.loads((out / "batch_summary.json").read_text())
    assert [s["status"] for s in summary["logs"]] == ["ok"] * 3
    assert output_files(out) == output_files(reference)


@pytest.mark.slow
def test_workers_end_with_the_batch_process(fault_logs: list[Path], tmp_path: Path) -> None:
    pipeline_file = fault_logs[0].parent / "pipe.toml"
    batch = start_batch([str(pipeline_file), *map(str, fault_logs), "-o", str(tmp_path / "o"),
                         "-j", "2"])
    workers = wait_for(lambda: len(pool_workers(batch.pid)) == 2 and pool_workers(batch.pid),
                       120, "two workers")
    assert isinstance(workers, list)
    os.kill(batch.pid, signal.SIGKILL)
    batch.communicate(timeout=30)
    wait_for(lambda: not any(alive(w) for w in workers), 15, "the workers to end")
