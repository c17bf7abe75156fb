"""The Ray engine: a batch on an existing Ray cluster, or on a Ray instance started here.

``address`` names the cluster (``host:port`` or ``auto``, as ``RAY_ADDRESS``); without
one, a local instance is started, bound to 127.0.0.1. Before any log is sent, every node
is asked to import camlog (the same version) and the filesystems the batch's URIs need,
so a cluster without them fails at once with one line instead of once per log; a cluster
that refuses the connection (a missing token, another Ray version, an address Ray replaced)
is one line with Ray's reason. Each log
is a task with ``cpus_per_log`` CPUs; Ray runs it again (``retries`` times) when its
worker or its node dies, and a log that runs out of retries is reported failed while the
others go on.
"""

from __future__ import annotations

import contextlib
import os
import re
import socket
import sys
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from replay import storage

from ..errors import ClusterError, UsageError
from .jobs import BatchJob, run_job

PROBE_TIMEOUT_S = 120.0
CONNECT_TIMEOUT_S = 5.0
#: how long a local Ray instance's GCS server may take to start (s; unless the user set
#: RAY_gcs_server_port_wait_time_s)
GCS_START_WAIT_S = 120


def run_on_ray(jobs: list[BatchJob], *, address: str | None, jobs_at_once: int | None,
               cpus_per_log: float, retries: int, done: Callable[[dict[str, Any]], None],
               show: Callable[[int, int], None], notes: list[str]) -> None:
    """Run ``jobs`` as Ray tasks; ``done`` gets each status, ``show`` (running, queued)."""
    try:
        import ray
    except ImportError:
        raise UsageError("--engine ray needs Ray: pip install 'camlog[ray]'") from None
    started_here = not ray.is_initialized()
    if started_here:
        _connect(ray, address, (jobs_at_once or 2) * cpus_per_log)
    try:
        nodes = _check_nodes(ray, address or "this machine", jobs)
        if len(nodes) > 1:
            local = [str(j.out_dir) for j in jobs[:1] if not storage.is_remote(j.out_dir)]
            local += [str(j.log) for j in jobs if not storage.is_remote(j.log)][:1]
            if local:
                notes.append(f"{len(nodes)} nodes share the work but {local[0]} is a local "
                             "path: every node must see it at that path (a shared "
                             "filesystem), or use a URI such as s3://bucket/...")
        task = ray.remote(run_job).options(num_cpus=cpus_per_log, max_retries=retries,
                                           retry_exceptions=False)
        _run(ray, task, jobs, limit=jobs_at_once or len(jobs), cpus_per_log=cpus_per_log,
             retries=retries, done=done, show=show)
    finally:
        if started_here:
            ray.shutdown()


def _connect(ray: Any, address: str | None, cpus: float) -> None:
    if address is None:
        _start_local(ray, cpus)
        return
    if address != "auto":
        _require_reachable(address)
        if not address.startswith("ray://"):
            target = _bootstrap_address(address)
            if target != address:
                _require_reachable(target, given=address)
            _require_admitted(ray, target, given=address)
    try:
        ray.init(address=address, log_to_driver=False, configure_logging=False)
    except Exception as err:  # Ray raises ConnectionError, RuntimeError, ValueError, …
        raise ClusterError(f"cannot connect to the Ray cluster at {address}: "
                          f"{_refusal(err, address)}") from None


def _start_local(ray: Any, cpus: float) -> None:
    """A Ray instance for this batch only, its servers bound to 127.0.0.1.

    Ray binds to the loopback address only in its single-machine mode, which it keys on
    a module constant (``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0`` before Ray is imported):
    the constant is switched for the start and restored.
    """
    from ray._private import ray_constants  # no public switch for this

    saved = getattr(ray_constants, "ENABLE_RAY_CLUSTER", None)
    if saved is not None:
        ray_constants.ENABLE_RAY_CLUSTER = False
    # Ray waits 30 s for its GCS server to bind its port, which a loaded machine can miss
    os.environ.setdefault("RAY_gcs_server_port_wait_time_s", str(GCS_START_WAIT_S))
    try:
        ray.init(num_cpus=max(1, round(cpus)), include_dashboard=False, log_to_driver=False,
                 configure_logging=False, _node_ip_address="127.0.0.1")
    except Exception as err:  # a server that did not come up in Ray's own time
        ray.shutdown()  # stops what did start: no server outlives the failure
        reason = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise ClusterError(f"cannot start a local Ray instance: {reason}") from None
    finally:
        if saved is not None:
            ray_constants.ENABLE_RAY_CLUSTER = saved


def _require_reachable(address: str, *, given: str | None = None) -> None:
    """A TCP connection to ``address``, which Ray made of ``given`` (when it differs)."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise UsageError(f"--address {address!r}: give HOST:PORT of the cluster's head or "
                          "'auto'")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), CONNECT_TIMEOUT_S):
            pass
    except OSError as err:
        reason = err.strerror or err
        if given is None:
            raise ClusterError(f"cannot reach the Ray cluster at {address}: {reason}") \
                from None
        raise ClusterError(
            f"cannot reach the Ray cluster at {given}: Ray connects to {address} instead "
            f"({reason}); it replaces 127.0.0.1 and localhost with this machine's address, "
            "where a head bound to 127.0.0.1 does not listen: name the head by another name "
            "of 127.0.0.1, such as the host name") from None


def _bootstrap_address(address: str) -> str:
    """The address ``ray.init`` connects to for ``address``."""
    from ray._private import services  # no public way to ask

    try:
        return str(services.canonicalize_bootstrap_address(address) or address)
    except Exception:  # Ray's own connect reports what is wrong with the address
        return address


def _require_admitted(ray: Any, address: str, *, given: str) -> None:
    """Ask the cluster's GCS once whether it takes this process: a refusal (a token that is
    missing or wrong) is said at once, where ``ray.init`` would retry for 20 s, print each
    attempt on stderr and then name neither the reason nor the address it was given."""
    client = getattr(ray._raylet, "GcsClient", None)  # no public way to ask
    if client is None:
        return
    try:
        with _quiet_stderr():  # Ray's C++ client logs each failed attempt there
            client(address=address)
    except Exception as err:
        raise ClusterError(f"cannot connect to the Ray cluster at {given}: "
                          f"{_refusal(err, given)}") from None


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def _refusal(err: BaseException, address: str) -> str:
    """Why Ray did not connect, as Ray says it: the innermost cause of ``err`` (its first
    sentence and notes), with what to do about a token, and the address Ray went to when
    it is not the one given (Ray replaces 127.0.0.1 with the machine's address)."""
    tried = re.search(r"Failed to connect to Ray cluster at (\S+)", str(err))
    cause = err
    while cause.__cause__ is not None:
        cause = cause.__cause__
    line = _one_line(cause).removeprefix("ray.exceptions.")
    first, *more = re.split(r"(?<=\.) ", line)
    reason = " ".join([first, *(m for m in more if m.startswith("Note:"))])  # no help text
    if type(cause).__name__ == "AuthenticationError" or "InvalidAuthToken" in line:
        reason = (f"authentication failed: {reason} (the cluster uses token authentication: "
                  "give its token in RAY_AUTH_TOKEN or a file named by RAY_AUTH_TOKEN_PATH, "
                  "with RAY_AUTH_MODE=token)")
    if tried and tried.group(1) != address:
        reason += f" (Ray tried {tried.group(1)} instead of {address})"
    return reason


def _needed_filesystems(jobs: Iterable[BatchJob]) -> list[str]:
    return sorted({storage.scheme(loc) for job in jobs for loc in (job.log, job.out_dir)
                   if storage.is_remote(loc)})


def _check_nodes(ray: Any, where: str, jobs: list[BatchJob]) -> list[str]:
    """Ask every live node to import camlog and the needed filesystems; their ids."""
    from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

    from replay._version import VERSION

    schemes = _needed_filesystems(jobs)

    def probe(schemes: list[str]) -> str:  # pickled by value: runs without camlog
        import importlib

        try:
            version = importlib.import_module("replay._version").VERSION
            importlib.import_module("camlog.batch.jobs")
            if schemes:
                fsspec = importlib.import_module("fsspec")
                for name in schemes:
                    fsspec.get_filesystem_class(name)
        except Exception as err:
            return f"error: {type(err).__name__}: {err}"
        return str(version)

    remote = ray.remote(num_cpus=0, max_retries=0)(probe)
    nodes = [n["NodeID"] for n in ray.nodes() if n.get("Alive")]
    refs = {remote.options(scheduling_strategy=NodeAffinitySchedulingStrategy(
        node_id, soft=False)).remote(schemes): node_id for node_id in nodes}
    ready, late = ray.wait(list(refs), num_returns=len(refs), timeout=PROBE_TIMEOUT_S)
    if late:
        raise ClusterError(f"the Ray cluster at {where}: node {refs[late[0]][:8]} did not "
                          f"start a worker within {PROBE_TIMEOUT_S:.0f} s")
    for ref in ready:
        try:
            answer = str(ray.get(ref))
        except Exception as err:
            answer = f"error: {_one_line(err)}"
        node = refs[ref][:8]
        if answer.startswith("error: "):
            raise ClusterError(
                f"the Ray cluster at {where} cannot run camlog on node {node}: "
                f"{_one_line(answer[7:])} (install camlog{'[cloud]' if schemes else ''} on "
                "every node, or give the job a runtime environment: see docs/batch.md)")
        if answer != VERSION:
            raise ClusterError(f"the Ray cluster at {where}: node {node} has camlog {answer}, "
                              f"this machine {VERSION}")
    return nodes


def _run(ray: Any, task: Any, jobs: list[BatchJob], *, limit: int, cpus_per_log: float,
         retries: int, done: Callable[[dict[str, Any]], None],
         show: Callable[[int, int], None]) -> None:
    waiting = list(reversed(jobs))
    in_flight: dict[Any, BatchJob] = {}
    last_count = 0.0
    while waiting or in_flight:
        while waiting and len(in_flight) < limit:
            job = waiting.pop()
            in_flight[task.remote(job)] = job
        ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=1.0)
        for ref in ready:
            job = in_flight.pop(ref)
            try:
                status = ray.get(ref)
            except Exception as err:  # worker or node lost more often than retries allow
                status = {"log": str(job.log), "out_dir": job.key, "status": "failed",
                          "steps": [], "seconds": 0.0, "node": "?",
                          "error": f"lost {retries + 1} times: {_one_line(err)}"}
            done(status)
        if time.monotonic() - last_count >= 1.0 or ready:
            last_count = time.monotonic()
            running = min(len(in_flight), _busy_slots(ray, cpus_per_log))
            show(running, len(in_flight) - running + len(waiting))


def _busy_slots(ray: Any, cpus_per_log: float) -> int:
    """Logs the cluster's CPUs in use could hold: the running count across the cluster."""
    try:
        used = ray.cluster_resources().get("CPU", 0) - ray.available_resources().get("CPU", 0)
    except Exception:  # a node going away mid-call
        return 0
    return int(used / cpus_per_log + 1e-6)


def _one_line(err: BaseException | str) -> str:
    """The message's first line, or a remote traceback's last (the exception itself)."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    if not lines:
        return type(err).__name__
    return lines[-1] if any(line.startswith("File ") for line in lines) else lines[0]
