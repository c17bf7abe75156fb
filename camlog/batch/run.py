"""``camlog batch``: one pipeline over many logs, in parallel processes or on Ray.

Each log gets ``OUTDIR/<log name>/`` with one folder per step and ``batch_status.json``.
A log whose status says it completed with the same input (size, mtime) and the same
pipeline is skipped. A failing log is recorded with its one-line error; the others go on.
"""

from __future__ import annotations

import json
import os
import time
import traceback
from collections.abc import Callable, Iterable
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from tqdm import tqdm

from processors.errors import ProcessorError
from recorder.errors import RecorderError
from replay.atomic import write_text_atomic
from replay.errors import ReplayError

from ..errors import CamlogError, InputError, UsageError
from .pipeline import Pipeline, run_step

STATUS_FILE = "batch_status.json"
ENGINES = ("process", "ray")
KNOWN_ERRORS = (CamlogError, ReplayError, ProcessorError, RecorderError, OSError, ValueError)


@dataclass(frozen=True)
class Job:
    """One log through the pipeline; everything a worker process needs."""

    log: Path
    out_dir: Path
    pipeline: Pipeline
    workers: int  # threads each step may use


def fingerprint(path: Path) -> dict[str, int]:
    """Size and newest mtime of a log file or rosbag2 directory."""
    files = [p for p in path.rglob("*") if p.is_file()] if path.is_dir() else [path]
    stats = [p.stat() for p in files]
    return {"bytes": sum(s.st_size for s in stats),
            "mtime_ns": max((s.st_mtime_ns for s in stats), default=0)}


def up_to_date(job: Job) -> dict[str, Any] | None:
    """The previous status when the outputs are complete for this input and pipeline."""
    status_path = job.out_dir / STATUS_FILE
    try:
        status = json.loads(status_path.read_text())
    except (OSError, json.JSONDecodeError):
        return None
    if not job.log.exists():
        return None
    same = (status.get("status") == "ok" and status.get("pipeline") == job.pipeline.digest()
            and status.get("input") == fingerprint(job.log))
    outputs_exist = all(Path(f).exists() for s in status.get("steps", [])
                        for f in s.get("files", []))
    return status if same and outputs_exist else None


#: thread pools of numerical libraries, sized per job so that parallel jobs do not
#: oversubscribe the cores (read when a worker process starts)
THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def run_job(job: Job) -> dict[str, Any]:
    """Run every step on one log; never raises for a bad log (the error is the status)."""
    import cv2

    cv2.setNumThreads(job.workers)  # OpenCV's own pool, besides the steps' worker threads
    started = time.perf_counter()
    previous = up_to_date(job)
    if previous is not None:
        return previous | {"status": "skipped", "seconds": 0.0}
    status: dict[str, Any] = {"log": str(job.log), "out_dir": str(job.out_dir), "steps": []}
    try:
        if not job.log.exists():
            raise InputError(f"{job.log} does not exist")
        status["input"] = fingerprint(job.log)
        logs: dict[str, Path] = {"log": job.log}
        current = job.log
        for index, step in enumerate(job.pipeline.steps):
            source = current if step.input == "previous" else logs[step.input]
            step_started = time.perf_counter()
            outcome = run_step(step, source, job.out_dir / f"{index + 1:02d}_{step.name}",
                               job.workers)
            if outcome.log is not None:
                logs[step.name] = outcome.log
                current = outcome.log
            status["steps"].append({
                "name": step.name, "run": step.run, "figures": outcome.figures,
                "files": [str(f) for f in outcome.files],
                "seconds": round(time.perf_counter() - step_started, 3)})
        status["status"] = "ok"
    except KNOWN_ERRORS as err:
        status |= {"status": "failed", "error": _one_line(err)}
    except Exception as err:  # a bug, not bad input: keep the trace for the report
        status |= {"status": "failed", "error": f"{type(err).__name__}: {_one_line(err)}",
                   "traceback": traceback.format_exc()}
    status["seconds"] = round(time.perf_counter() - started, 3)
    status["pipeline"] = job.pipeline.digest()
    job.out_dir.mkdir(parents=True, exist_ok=True)
    write_text_atomic(job.out_dir / STATUS_FILE, json.dumps(status, indent=1) + "\n")
    return status


def _one_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__


def plan_jobs(pipeline: Pipeline, logs: Iterable[Path], out_dir: Path, jobs: int) -> list[Job]:
    """One job per log, each with its own output folder (names made unique)."""
    workers = max(1, (os.cpu_count() or 2) // max(1, jobs))
    planned: list[Job] = []
    used: set[str] = set()
    for log in logs:
        name = log.name.removesuffix(".mcap").removesuffix(".bag") or "log"
        unique, n = name, 2
        while unique in used:
            unique, n = f"{name}_{n}", n + 1
        used.add(unique)
        planned.append(Job(log, out_dir / unique, pipeline, workers))
    return planned


def _run_processes(jobs: list[Job], n: int, done: Callable[[dict[str, Any]], None]) -> None:
    # spawn: workers start clean instead of inheriting this process's threads and locks;
    # they read the thread-pool sizes from the environment when they start
    saved = {name: os.environ.get(name) for name in THREAD_ENV}
    os.environ.update(dict.fromkeys(THREAD_ENV, str(jobs[0].workers if jobs else 1)))
    try:
        with ProcessPoolExecutor(max_workers=n, mp_context=get_context("spawn")) as pool:
            futures: dict[Future[dict[str, Any]], Job] = {
                pool.submit(run_job, j): j for j in jobs}
            for future in as_completed(futures):
                done(future.result())
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _run_ray(jobs: list[Job], n: int, done: Callable[[dict[str, Any]], None]) -> None:
    try:
        import ray
    except ImportError:
        raise UsageError("--engine ray needs Ray: pip install 'camlog[ray]'") from None
    started_here = not ray.is_initialized()
    if started_here:
        threads = str(jobs[0].workers if jobs else 1)
        ray.init(num_cpus=n, include_dashboard=False, log_to_driver=False,
                 configure_logging=False,
                 runtime_env={"env_vars": dict.fromkeys(THREAD_ENV, threads)})
    try:
        remote = ray.remote(num_cpus=1)(run_job)
        pending = [remote.remote(job) for job in jobs]
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            done(ray.get(ready[0]))
    finally:
        if started_here:
            ray.shutdown()


@dataclass
class BatchResult:
    """What a batch run produced: one status per log, wall time, the summary file."""
    statuses: list[dict[str, Any]]
    wall_s: float
    summary_path: Path

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The statuses of the logs that failed."""
        return [s for s in self.statuses if s["status"] == "failed"]


def run_batch(pipeline: Pipeline, logs: list[Path], out_dir: Path, *, jobs: int = 2,
              engine: str = "process", progress: bool | None = None) -> BatchResult:
    """Run ``pipeline`` over ``logs``; statuses come back in the order of ``logs``."""
    if engine not in ENGINES:
        raise UsageError(f"unknown engine {engine!r} (use {' or '.join(ENGINES)})")
    if jobs < 1:
        raise UsageError(f"-j must be at least 1, got {jobs}")
    if not logs:
        raise UsageError("give at least one log")
    if out_dir.exists() and not out_dir.is_dir():
        raise UsageError(f"output {out_dir} exists and is not a directory")
    out_dir.mkdir(parents=True, exist_ok=True)
    planned = plan_jobs(pipeline, logs, out_dir, jobs)
    results: dict[str, dict[str, Any]] = {}
    bar = tqdm(total=len(planned), unit="log", desc="batch", leave=False,
               disable=None if progress is None else not progress)

    def done(status: dict[str, Any]) -> None:
        results[status["out_dir"]] = status
        bar.update()

    started = time.perf_counter()
    try:
        if engine == "ray":
            _run_ray(planned, jobs, done)
        else:
            _run_processes(planned, jobs, done)
    finally:
        bar.close()
    statuses = [results[str(j.out_dir)] for j in planned]
    wall = time.perf_counter() - started
    summary_path = out_dir / "batch_summary.json"
    write_text_atomic(summary_path, json.dumps({"pipeline": pipeline.source, "engine": engine,
                                                "jobs": jobs, "wall_s": round(wall, 3),
                                                "logs": statuses}, indent=1) + "\n")
    return BatchResult(statuses, wall, summary_path)


def summary_table(result: BatchResult) -> str:
    """One line per log: status, time and the steps' key figures (or the error)."""
    rows = [("log", "status", "time s", "figures")]
    for s in result.statuses:
        if s["status"] == "failed":
            detail = s.get("error", "")
        else:
            detail = "; ".join(
                f"{step['name']}: " + ", ".join(f"{k} {v}" for k, v in step["figures"].items())
                for step in s.get("steps", []) if step.get("figures"))
        rows.append((Path(s["log"]).name, s["status"], f"{s.get('seconds', 0):.1f}", detail))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    lines = [f"{r[0]:{widths[0]}}  {r[1]:{widths[1]}}  {r[2]:>{widths[2]}}  {r[3]}" for r in rows]
    ok = sum(s["status"] != "failed" for s in result.statuses)
    lines.append(f"{ok} of {len(result.statuses)} logs done ({len(result.failed)} failed) in "
                 f"{result.wall_s:.1f} s; summary: {result.summary_path}")
    return "\n".join(lines)
