"""``camlog batch``: one pipeline over many logs, in parallel processes or on Ray.

Each log gets ``OUTDIR/<log name>/`` with one folder per step and ``batch_status.json``
(see :mod:`camlog.batch.jobs` for what makes a log complete and when it is skipped).
Logs and OUTDIR are paths or URIs (``s3://bucket/logs/*.mcap``). A failing log is
recorded with its one-line error; the others go on. The process engine
(:mod:`camlog.batch.local`) is the default; :mod:`camlog.batch.cluster` runs on Ray.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from tqdm import tqdm

from replay import storage
from replay.storage import Location

from ..errors import UsageError
from .jobs import BatchJob
from .pipeline import Pipeline

ENGINES = ("process", "ray")
SUMMARY_FILE = "batch_summary.json"
DEFAULT_JOBS = 2


def log_name(log: Location) -> str:
    """Output folder name of a log: its file or folder name without the log suffix."""
    name = str(log).rstrip("/").replace("\\", "/").rsplit("/", 1)[-1]
    return name.removesuffix(".mcap").removesuffix(".bag") or "log"


def plan_jobs(pipeline: Pipeline, logs: Iterable[Location], out_dir: Location,
              workers: int) -> list[BatchJob]:
    """One job per log, each with its own output folder (names made unique)."""
    planned: list[BatchJob] = []
    used: set[str] = set()
    for log in logs:
        name = log_name(log)
        unique, n = name, 2
        while unique in used:
            unique, n = f"{name}_{n}", n + 1
        used.add(unique)
        planned.append(BatchJob(log, storage.join(out_dir, unique), pipeline, workers))
    return planned


@dataclass
class BatchResult:
    """Statuses in the order of the logs, wall time, and where the summary went."""

    statuses: list[dict[str, Any]]
    wall_s: float
    summary_path: Location
    first_result_s: float | None = None
    notes: list[str] = field(default_factory=list)

    @property
    def failed(self) -> list[dict[str, Any]]:
        """Statuses of the logs that failed."""
        return [s for s in self.statuses if s["status"] == "failed"]


@dataclass(frozen=True)
class Engine:
    """Where the logs run: local processes or Ray (``name``); ``address``: an existing Ray
    cluster (``host:port`` or ``auto``); ``cpus_per_log``: the CPUs each log's Ray task asks
    for; ``retries``: how often a log whose worker or node died is run again."""

    name: str = "process"
    address: str | None = None
    cpus_per_log: float = 1.0
    retries: int = 2


def run_batch(pipeline: Pipeline, logs: Sequence[Location], out_dir: Location, *,
              jobs: int | None = None, engine: Engine = Engine(),
              progress: bool | None = None) -> BatchResult:
    """Run ``pipeline`` over ``logs`` on ``engine``; statuses come back in the order of
    ``logs``.

    ``jobs``: logs at once (default 2; on an existing Ray cluster, as many as its CPUs
    hold).
    """
    address, cpus_per_log, retries = engine.address, engine.cpus_per_log, engine.retries
    engine_name = engine.name
    if engine_name not in ENGINES:
        raise UsageError(f"unknown engine {engine_name!r} (use {' or '.join(ENGINES)})")
    if jobs is not None and jobs < 1:
        raise UsageError(f"-j must be at least 1, got {jobs}")
    if cpus_per_log <= 0:
        raise UsageError(f"--cpus-per-log must be positive, got {cpus_per_log}")
    if retries < 0:
        raise UsageError(f"--retries must be 0 or more, got {retries}")
    if address is not None and engine_name != "ray":
        raise UsageError("--address needs --engine ray")
    logs = [found for log in logs for found in storage.expand(str(log))] \
        if any(storage.is_remote(log) for log in logs) else logs
    if not logs:
        raise UsageError("give at least one log")
    if not storage.is_remote(out_dir):
        out_dir = storage.local_path(out_dir)
        if out_dir.exists() and not out_dir.is_dir():
            raise UsageError(f"output {out_dir} exists and is not a directory")
        out_dir.mkdir(parents=True, exist_ok=True)
    at_once = jobs or DEFAULT_JOBS
    workers = max(1, round(cpus_per_log)) if engine_name == "ray" else \
        max(1, (os.cpu_count() or 2) // at_once)
    planned = plan_jobs(pipeline, logs, out_dir, workers)
    results: dict[str, dict[str, Any]] = {}
    bar = tqdm(total=len(planned), unit="log", desc="batch", leave=False,
               disable=None if progress is None else not progress)
    started = time.perf_counter()
    first: list[float] = []
    notes: list[str] = []

    def done(status: dict[str, Any]) -> None:
        results[status["out_dir"]] = status
        first.append(time.perf_counter() - started)
        bar.update()

    def show(running: int, queued: int) -> None:
        failed = sum(s["status"] == "failed" for s in results.values())
        bar.set_postfix_str(f"running {running}, queued {queued}, failed {failed}",
                            refresh=True)

    try:
        if engine_name == "ray":
            from .cluster import run_on_ray

            run_on_ray(planned, address=address, jobs_at_once=jobs if address else at_once,
                       cpus_per_log=cpus_per_log, retries=retries, done=done, show=show,
                       notes=notes)
        else:
            from .local import run_processes

            run_processes(planned, at_once, done, show, attempts=retries + 1)
    finally:
        bar.close()
    statuses = [results[j.key] for j in planned]
    wall = time.perf_counter() - started
    summary_path = storage.join(out_dir, SUMMARY_FILE)
    summary = {"pipeline": pipeline.source, "engine": engine_name, "address": address,
               "jobs": jobs, "wall_s": round(wall, 3), "logs": statuses}
    storage.write_bytes(summary_path, (json.dumps(summary, indent=1) + "\n").encode())
    return BatchResult(statuses, wall, summary_path, min(first, default=None), notes)


def summary_table(result: BatchResult) -> str:
    """One line per log: status, node, time and the steps' key figures (or the error)."""
    rows = [("log", "status", "node", "time s", "figures")]
    for s in result.statuses:
        if s["status"] == "failed":
            detail = s.get("error", "")
        else:
            detail = "; ".join(
                f"{step['name']}: " + ", ".join(f"{k} {v}" for k, v in step["figures"].items())
                for step in s.get("steps", []) if step.get("figures"))
        name = str(s["log"]).rstrip("/").rsplit("/", 1)[-1]
        rows.append((name, s["status"], str(s.get("node", "")), f"{s.get('seconds', 0):.1f}",
                     detail))
    widths = [max(len(r[i]) for r in rows) for i in range(4)]
    lines = [f"{r[0]:{widths[0]}}  {r[1]:{widths[1]}}  {r[2]:{widths[2]}}  "
             f"{r[3]:>{widths[3]}}  {r[4]}" for r in rows]
    ok = sum(s["status"] != "failed" for s in result.statuses)
    lines.append(f"{ok} of {len(result.statuses)} logs done ({len(result.failed)} failed) in "
                 f"{result.wall_s:.1f} s; summary: {result.summary_path}")
    return "\n".join(lines)
