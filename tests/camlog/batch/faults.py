"""Helpers for the fault tests: batches in their own process, their outputs compared."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from camlog.cli import main

from .test_run import SCENARIOS


def record_logs(folder: Path, count: int, frames: int) -> list[Path]:
    """``count`` short stereo_unsynced recordings (seeds 1…count) at 160x120."""
    logs = []
    for seed in range(1, count + 1):
        path = folder / f"cam{seed}.mcap"
        assert main(["record", str(SCENARIOS / "stereo_unsynced.toml"), "-o", str(path),
                     "--frames", str(frames), "--resolution", "160x120", "--seed", str(seed),
                     "--no-progress"]) == 0
        logs.append(path)
    return logs


def start_batch(argv: list[str], env: dict[str, str] | None = None) -> subprocess.Popen[str]:
    """``camlog batch ARGV…`` in its own process (its output piped)."""
    return subprocess.Popen([sys.executable, "-m", "camlog", "batch", *argv, "--no-progress"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)


def wait_for(condition: Callable[[], object], timeout_s: float, what: str) -> object:
    """Poll ``condition`` until it returns something true."""
    deadline = time.monotonic() + timeout_s
    while True:
        found = condition()
        if found:
            return found
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.05)


def children(pid: int) -> list[int]:
    """Direct child processes of ``pid`` (Linux /proc)."""
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(c) for c in text.split()]


def cmdline(pid: int) -> str:
    """A process's command line ('' once it is gone)."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def pool_workers(pid: int) -> list[int]:
    """The spawned pool workers of a batch process."""
    return [c for c in children(pid) if "spawn_main" in cmdline(c)
            and "resource_tracker" not in cmdline(c)]


def output_files(out: Path) -> dict[str, bytes]:
    """Every output file below a batch folder but the statuses and summary, by relative
    name; the info step's first line (the path it read) is left out."""
    files = {}
    for path in sorted(out.rglob("*")):
        if path.is_file() and not path.name.startswith("batch_"):
            data = path.read_bytes()
            if path.name == "info.txt":
                data = data.split(b"\n", 1)[1]
            files[path.relative_to(out).as_posix()] = data
    return files


def kill_when(condition: Callable[[], int | None], timeout_s: float, what: str) -> int:
    """Wait until ``condition`` names a process, then kill it (SIGKILL); its pid."""
    pid = int(wait_for(condition, timeout_s, what))  # type: ignore[call-overload]
    os.kill(pid, 9)
    return pid
