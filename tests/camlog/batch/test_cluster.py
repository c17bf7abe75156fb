"""camlog batch on a real two-node Ray cluster on this machine; one node dies mid-batch.

The head is started with ``ray start --head`` bound to 127.0.0.1 and a second node joins
with ``ray start --address``, each with its own temp dir and one CPU. Ray rewrites the
addresses ``127.0.0.1`` and ``localhost`` to the machine's outward address (where a
loopback-bound head does not listen), so the node and the batch reach the head through
another name of 127.0.0.1 — the host name, where /etc/hosts maps it there; without such
a name the cluster runs on Ray's default node address instead.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from camlog.batch.run import run_batch
from camlog.requests.batch import BatchRequest
from tests.slow import renders

from .faults import alive, cmdline, output_files, start_batch, wait_for
from .test_s3 import free_port

RAY = str(Path(sys.executable).parent / "ray")


def loopback_name() -> str | None:
    """A name of 127.0.0.1 that Ray does not rewrite (not 'localhost')."""
    for name in sorted({socket.gethostname(), socket.getfqdn()}):
        try:
            if name != "localhost" and socket.gethostbyname(name) == "127.0.0.1":
                return name
        except OSError:
            continue
    return None


@dataclass
class Cluster:
    """A two-node Ray cluster: each node's session (its processes), address, environment."""

    address: str
    env: dict[str, str]
    head: int
    worker: int


def start_node(args: list[str], env: dict[str, str], temp_dir: Path) -> int:
    """``ray start ARGS…`` in a new session; the session id, which every process of the
    node keeps (Ray's workers get process groups of their own)."""
    node = subprocess.Popen(
        [RAY, "start", *args, "--num-cpus", "1", "--object-store-memory", "100000000",
         "--temp-dir", str(temp_dir), "--disable-usage-stats"],
        env=env, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True)
    output, _ = node.communicate(timeout=240)
    assert node.returncode == 0, output[-3000:]
    return node.pid


def session_of(pid: int) -> int | None:
    """The session a process belongs to (None once it is gone)."""
    try:
        return os.getsid(pid)
    except ProcessLookupError:
        return None


def in_session(session: int) -> list[int]:
    """The live processes of a session."""
    pids = [int(p.name) for p in Path("/proc").iterdir() if p.name.isdigit()]
    return [pid for pid in pids if session_of(pid) == session and alive(pid)]


def end_session(session: int) -> None:
    """Kill every process of a session (SIGKILL, as a machine dies) and wait for them."""
    for pid in in_session(session):
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
    wait_for(lambda: not in_session(session), 30, f"session {session} to end")


@pytest.fixture(scope="module")
@renders
def cluster() -> Iterator[Cluster]:
    """Head (127.0.0.1) and a second node, one CPU each, token auth with a fresh token."""
    temp = Path(tempfile.mkdtemp(prefix="rc", dir="/tmp"))  # Ray's socket paths are short
    name = loopback_name()
    port = free_port()
    env = os.environ | {
        "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32),
        "RAY_USAGE_STATS_ENABLED": "0",
        # notice a dead node within seconds, not Ray's default half a minute
        "RAY_health_check_period_ms": "500", "RAY_health_check_timeout_ms": "1000",
        "RAY_health_check_failure_threshold": "3"}
    head_env = env | {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"} if name else env
    groups: list[int] = []
    try:
        groups.append(start_node(["--head", "--node-ip-address", "127.0.0.1", "--port",
                                  str(port), "--include-dashboard", "false"],
                                 head_env, temp / "head"))
        address = f"{name or '127.0.0.1'}:{port}"
        groups.append(start_node(["--address", address], env, temp / "node"))
        yield Cluster(address, env, groups[0], groups[1])
    finally:
        for group in reversed(groups):
            end_session(group)
        shutil.rmtree(temp, ignore_errors=True)


@pytest.fixture
def cluster_logs(short_logs: list[Path]) -> list[Path]:
    """The six short logs."""
    return short_logs


@pytest.mark.slow
def test_a_cluster_without_a_needed_filesystem_is_one_line(
    cluster: Cluster, cluster_logs: list[Path], tmp_path: Path
) -> None:
    # gs:// needs gcsfs, which camlog does not install: every node lacks it
    batch = start_batch([str(cluster_logs[0].parent / "pipe.toml"), "gs://bucket/run.mcap",
                         "-o", str(tmp_path / "o"), "--engine", "ray", "--address",
                         cluster.address], env=cluster.env)
    _, stderr = batch.communicate(timeout=180)
    assert batch.returncode == 1
    errors = [line for line in stderr.splitlines() if "camlog batch: error:" in line]
    assert len(errors) == 1, stderr
    assert "cannot run camlog on node" in errors[0] and "gcsfs" in errors[0]


@pytest.mark.slow
def test_a_batch_without_the_clusters_token_says_authentication_failed(
    cluster: Cluster, cluster_logs: list[Path], tmp_path: Path
) -> None:
    """The cluster uses token auth; a batch from a home with no token is refused at once,
    in one line that says why, as Ray reports it."""
    home = tmp_path / "home"
    home.mkdir()
    env = {k: v for k, v in cluster.env.items() if not k.startswith("RAY_AUTH")}
    started = time.monotonic()
    batch = start_batch([str(cluster_logs[0].parent / "pipe.toml"), str(cluster_logs[0]),
                         "-o", str(tmp_path / "o"), "--engine", "ray", "--address",
                         cluster.address], env=env | {"HOME": str(home)})
    _, stderr = batch.communicate(timeout=120)
    assert batch.returncode == 1
    (line,) = stderr.splitlines()
    assert line.startswith(f"camlog batch: error: cannot connect to the Ray cluster at "
                           f"{cluster.address}: authentication failed: "), line
    assert "InvalidAuthToken" in line and "RAY_AUTH_TOKEN" in line, line
    assert time.monotonic() - started < 30
    assert not (home / ".ray").exists()


@pytest.mark.slow
def test_a_node_killed_mid_batch_changes_no_output(
    cluster: Cluster, cluster_logs: list[Path], tmp_path: Path
) -> None:
    pipeline_file = cluster_logs[0].parent / "pipe.toml"
    reference = tmp_path / "reference"
    assert not run_batch(BatchRequest(pipeline=pipeline_file, logs=tuple(cluster_logs),
                                      output=reference, jobs=2, progress=False)).failed
    out = tmp_path / "out"
    started = time.monotonic()
    # the cluster named as users do, through RAY_ADDRESS
    batch = start_batch([str(pipeline_file), *map(str, cluster_logs), "-o", str(out),
                         "--engine", "ray"], env=cluster.env | {"RAY_ADDRESS": cluster.address})

    def log_running_on_second_node() -> bool:
        return any(cmdline(pid).startswith("ray::run_job") for pid in in_session(cluster.worker))

    wait_for(log_running_on_second_node, 240, "a log on the second node")
    end_session(cluster.worker)
    stdout, stderr = batch.communicate(timeout=300)
    assert batch.returncode == 0, stderr[-3000:]
    assert "6 of 6 logs done (0 failed)" in stdout, stdout
    summary = json.loads((out / "batch_summary.json").read_text())
    assert [s["status"] for s in summary["logs"]] == ["ok"] * 6
    assert summary["address"] == cluster.address
    assert all(s["node"] and s["seconds"] > 0 for s in summary["logs"])
    assert output_files(out) == output_files(reference)
    assert time.monotonic() - started < 300



class _SlowRay:
    """The part of Ray's API the local start uses, whose servers never come up in time (as
    on a loaded machine): ``init`` fails as Ray's does, ``shutdown`` is counted."""

    def __init__(self) -> None:
        self.shutdowns = 0

    def init(self, **_options: object) -> None:
        raise RuntimeError("Timed out waiting for file /tmp/ray/session_x/gcs_server_port\n"
                           "more detail")

    def shutdown(self) -> None:
        self.shutdowns += 1


#: Ray's own setting of how long to wait for its GCS server (its spelling, lower case)
GCS_WAIT = "RAY_gcs_server_port_wait_time_s"


@pytest.mark.slow
def test_a_local_ray_that_misses_its_start_is_stopped_and_one_line(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from camlog.batch.cluster import GCS_START_WAIT_S, _connect
    from camlog.errors import ClusterError

    monkeypatch.delenv(GCS_WAIT, raising=False)
    slow = _SlowRay()
    with pytest.raises(ClusterError) as raised:
        _connect(slow, None, 2)
    assert str(raised.value) == ("cannot start a local Ray instance: Timed out waiting for "
                                 "file /tmp/ray/session_x/gcs_server_port")
    assert slow.shutdowns == 1  # what did start is stopped
    assert os.environ.get(GCS_WAIT) == str(GCS_START_WAIT_S)
    monkeypatch.setenv(GCS_WAIT, "7")  # the user's own setting wins
    with pytest.raises(ClusterError):
        _connect(_SlowRay(), None, 2)
    assert os.environ.get(GCS_WAIT) == "7"
