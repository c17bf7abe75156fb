"""One log through a pipeline, on whichever machine runs it: the worker side of a batch.

Inputs and outputs are paths or URIs (:mod:`replay.storage`). A log's folder holds one
folder per step and ``batch_status.json``, the completion marker: it is deleted before a
log is (re)run and written — whole, in one atomic write — only after every output is in
place, with the input's identity (size, mtime or ETag), the pipeline's digest and every
output's size. A log is skipped only when that marker says ``ok`` for the same input and
pipeline and every output it lists is there with its size, so a run cut short anywhere
(a killed worker, a lost node) is never taken for a complete one.

Remote outputs are written to a local scratch folder and uploaded when the log is done;
MCAP inputs on object storage are read in place with range requests, other formats from
a temporary download (the status says so).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from processors.errors import ProcessorError
from recorder.errors import RecorderError
from replay import storage
from replay.bounded import MAX_FILE_BYTES, json_loads
from replay.errors import ReplayError
from replay.leftovers import leftovers_in
from replay.storage import Location

from ..errors import CamlogError, InputError
from .pipeline import Pipeline, run_step

STATUS_FILE = "batch_status.json"
KNOWN_ERRORS = (CamlogError, ReplayError, ProcessorError, RecorderError, OSError, ValueError)


@dataclass(frozen=True)
class BatchJob:
    """One log through the pipeline; everything a worker needs (paths or URIs)."""

    log: Location
    out_dir: Location
    pipeline: Pipeline
    workers: int  # threads each step may use

    @property
    def key(self) -> str:
        """The job's name in statuses and summaries: its output folder."""
        return str(self.out_dir)


def _file_size(location: str) -> int | None:
    try:
        return storage.size(location) if storage.exists(location) else None
    except (OSError, ReplayError):
        return None


def up_to_date(job: BatchJob) -> dict[str, Any] | None:
    """The previous status when the outputs are complete for this input and pipeline."""
    try:
        status = json_loads(storage.read_bytes(storage.join(job.out_dir, STATUS_FILE)),
                            STATUS_FILE, ValueError, max_bytes=MAX_FILE_BYTES)
        if not storage.exists(job.log):
            return None
        same = (status.get("status") == "ok"
                and status.get("pipeline") == job.pipeline.digest()
                and status.get("input") == storage.identity(job.log))
    except (OSError, ReplayError, ValueError):  # ValueError: not JSON
        return None
    complete = all(
        len(s.get("files", [])) == len(s.get("bytes", ()))
        and all(_file_size(f) == n for f, n in zip(s["files"], s["bytes"], strict=True))
        for s in status.get("steps", []))
    return status if same and complete else None


def node_name() -> str:
    """Which machine (and, on Ray, which node) runs this process."""
    try:
        import ray

        if ray.is_initialized():
            context = ray.get_runtime_context()
            return f"{socket.gethostname()}/{context.get_node_id()[:8]}"
    except ImportError:
        pass
    return socket.gethostname()


def run_job(job: BatchJob) -> dict[str, Any]:
    """Run every step on one log; never raises for a bad log (the error is the status)."""
    import cv2

    cv2.setNumThreads(job.workers)  # OpenCV's own pool, besides the steps' worker threads
    started = time.perf_counter()
    where = {"node": node_name(), "pid": os.getpid()}
    previous = up_to_date(job)
    if previous is not None:
        return previous | where | {"status": "skipped", "seconds": 0.0, "out_dir": job.key}
    status: dict[str, Any] = {"log": str(job.log), "out_dir": job.key, "steps": []}
    marker = storage.join(job.out_dir, STATUS_FILE)
    # a scratch folder only for remote inputs or outputs: a worker killed mid-log leaves
    # nothing behind in the system's temp folder when everything is local
    remote = storage.is_remote(job.log) or storage.is_remote(job.out_dir)
    scratch_dir = tempfile.TemporaryDirectory(prefix="camlog-batch-") if remote else None
    with scratch_dir or contextlib.nullcontext() as scratch_name:
        try:
            storage.remove(marker)  # from now on the folder is not complete
            _run_steps(job, status, Path(scratch_name) if scratch_name else None)
            status["status"] = "ok"
        except KNOWN_ERRORS as err:
            status |= {"status": "failed", "error": _one_line(err)}
        except Exception as err:  # a bug, not bad input: keep the trace for the report
            status |= {"status": "failed", "error": f"{type(err).__name__}: {_one_line(err)}",
                       "traceback": traceback.format_exc()}
    status |= where | {"seconds": round(time.perf_counter() - started, 3),
                       "pipeline": job.pipeline.digest()}
    try:
        storage.write_bytes(marker, (json.dumps(status, indent=1) + "\n").encode())
    except (OSError, ReplayError) as err:
        status |= {"status": "failed", "error": f"cannot write its status: {_one_line(err)}"}
    return status


def _run_steps(job: BatchJob, status: dict[str, Any], scratch: Path | None) -> None:
    """The steps, into the output folder (local) or a scratch folder then uploaded."""
    remote_out = storage.is_remote(job.out_dir)
    out = scratch / "out" if remote_out and scratch else storage.local_path(job.out_dir)
    if not storage.exists(job.log):
        raise InputError(f"{job.log} does not exist")
    status["input"] = storage.identity(job.log)
    source = _stage_input(job.log, scratch, status)
    logs: dict[str, Location] = {"log": source}
    current = source
    for index, step in enumerate(job.pipeline.steps):
        step_input = current if step.input == "previous" else logs[step.input]
        step_started = time.perf_counter()
        folder = f"{index + 1:02d}_{step.name}"
        _clear_earlier_attempt(out / folder)
        outcome = run_step(step, step_input, out / folder, job.workers)
        if outcome.log is not None:
            logs[step.name] = outcome.log
            current = outcome.log
        files = [str(f) for f in outcome.files]
        if remote_out:
            files = [str(storage.join(job.out_dir, Path(f).relative_to(out).as_posix()))
                     for f in files]
        status["steps"].append({
            "name": step.name, "run": step.run, "figures": outcome.figures, "files": files,
            "bytes": [storage.size(f) for f in outcome.files],
            "seconds": round(time.perf_counter() - step_started, 3)})
    if remote_out:
        storage.upload(out, str(job.out_dir))


def _clear_earlier_attempt(folder: Path) -> None:
    """Remove the temporary outputs an earlier attempt at this log left in its step folder
    (a worker killed mid-step): the folder is the batch's own, and the step makes them again
    from its input."""
    if not folder.is_dir():
        return
    for leftover in leftovers_in(folder):
        if leftover.path.is_dir():
            shutil.rmtree(leftover.path, ignore_errors=True)
        else:
            leftover.path.unlink(missing_ok=True)


def _stage_input(log: Location, scratch: Path | None, status: dict[str, Any]) -> Location:
    """The log itself, unless it is remote and not one MCAP file: then a local copy (made
    once here rather than by every step that reads it)."""
    from replay.formats.mcap import MAGIC as MCAP_MAGIC

    if not storage.is_remote(log) or scratch is None:
        return log
    uri = str(log)
    if not storage.is_dir(uri):
        with storage.open_remote(uri) as file:
            if file.read(len(MCAP_MAGIC)) == MCAP_MAGIC:
                return log  # read in place, with range requests
    status["notes"] = [f"{uri} was downloaded (only MCAP is read in place)"]
    return storage.download(uri, scratch)


def _one_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__
