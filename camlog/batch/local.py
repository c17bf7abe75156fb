"""The process engine: one machine, a pool of spawned worker processes.

Workers end when the batch process ends (they watch their parent), so a killed batch
leaves nothing running. A worker that dies (a crash in native code, the OOM killer) takes
the pool down with it; the logs it was running are retried in a new pool, at most
``attempts`` times each, and the logs that had not started yet are simply run again.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from multiprocessing import get_context
from typing import Any

from .jobs import BatchJob, run_job

#: thread pools of numerical libraries, sized per job so that parallel jobs do not
#: oversubscribe the cores (read when a worker process starts)
THREAD_ENV = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
PARENT_POLL_S = 0.5
#: how often the batch looks at which logs started and finished: the live counts beside the
#: progress bar follow a log that takes half a second
POLL_S = 0.1

#: in a worker: "started", the queue that tells the batch which log it started
_WORKER: dict[str, Any] = {}


def watch_parent(parent_pid: int) -> None:
    """End this process as soon as ``parent_pid`` is no longer its parent."""
    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(PARENT_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="watch-parent", daemon=True).start()


def _init_worker(parent_pid: int, started: Any) -> None:
    watch_parent(parent_pid)
    _WORKER["started"] = started


def _run_in_worker(job: BatchJob) -> dict[str, Any]:
    _WORKER["started"].put(job.key)
    return run_job(job)


def crashed_status(job: BatchJob, attempts: int, why: str) -> dict[str, Any]:
    """Status of a log whose worker died ``attempts`` times."""
    return {"log": str(job.log), "out_dir": job.key, "status": "failed", "steps": [],
            "error": f"its worker died {attempts} times ({why})",
            "node": socket.gethostname(), "seconds": 0.0}


def run_processes(jobs: list[BatchJob], n: int, done: Callable[[dict[str, Any]], None],
                  show: Callable[[int, int], None], *, attempts: int = 3) -> None:
    """Run ``jobs`` in ``n`` processes; ``done`` gets each status, ``show`` (running,
    queued) counts as they change."""
    # spawn: workers start clean instead of inheriting this process's threads and locks;
    # they read the thread-pool sizes from the environment when they start
    saved = {name: os.environ.get(name) for name in THREAD_ENV}
    os.environ.update(dict.fromkeys(THREAD_ENV, str(jobs[0].workers if jobs else 1)))
    context = get_context("spawn")
    started = context.SimpleQueue()
    tries: dict[str, int] = {}
    remaining = list(jobs)
    try:
        while remaining:
            with ProcessPoolExecutor(max_workers=n, mp_context=context,
                                     initializer=_init_worker,
                                     initargs=(os.getpid(), started)) as pool:
                futures: dict[Future[dict[str, Any]], BatchJob] = {
                    pool.submit(_run_in_worker, job): job for job in remaining}
                remaining = _collect(futures, started, tries=tries, attempts=attempts,
                                     done=done, show=show)
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _collect(futures: dict[Future[dict[str, Any]], BatchJob], started: Any, *,
             tries: dict[str, int], attempts: int, done: Callable[[dict[str, Any]], None],
             show: Callable[[int, int], None]) -> list[BatchJob]:
    """Wait for one pool's jobs; the jobs to run again in a new pool."""
    running: set[str] = set()
    again: list[BatchJob] = []
    pending = set(futures)
    while pending:
        finished, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
        while not started.empty():
            running.add(started.get())
        for future in finished:
            job = futures[future]
            try:
                status = future.result()
            except BrokenProcessPool as err:
                if job.key in running or not running:  # not running: it broke at start
                    tries[job.key] = tries.get(job.key, 0) + 1
                    if tries[job.key] >= attempts:
                        done(crashed_status(job, tries[job.key], str(err).split(".")[0]))
                        continue
                again.append(job)
                continue
            running.discard(job.key)
            done(status)
        in_pool = {futures[f].key for f in pending}
        show(len(running & in_pool), len(in_pool - running))
    return again
