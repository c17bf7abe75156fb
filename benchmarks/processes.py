"""Whole processes run to their end, as a user runs them: wall and CPU time, peak memory.

Shared by the benchmarks that time or weigh commands (:mod:`.peers`, :mod:`.view_memory`).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Run", "clear", "run_once", "tool"]


def tool(name: str) -> list[str]:
    """The console script ``name`` installed beside this Python (as a user runs it)."""
    script = Path(sys.executable).with_name(name)
    if script.is_file():
        return [str(script)]
    found = shutil.which(name)
    if found is None:
        raise SystemExit(f"{name} is not installed (pip install -e '.[test]')")
    return [found]


@dataclass(frozen=True)
class Run:
    """One finished process: wall and CPU seconds, peak resident MB, exit status."""

    wall_s: float
    cpu_s: float
    peak_mb: float
    status: int


def run_once(argv: Sequence[str], *, expect: int = 0) -> Run:
    """Run ``argv`` to its end, its output discarded; fail loudly on an unexpected status."""
    with tempfile.TemporaryFile() as err:
        started = time.perf_counter()
        proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=err)
        _, wait_status, usage = os.wait4(proc.pid, 0)
        wall_s = time.perf_counter() - started
        proc.returncode = status = os.waitstatus_to_exitcode(wait_status)
        if status != expect:
            err.seek(0)
            tail = err.read().decode(errors="replace")[-1500:]
            raise SystemExit(f"{' '.join(argv)} exited {status} (expected {expect}):\n{tail}")
    return Run(wall_s, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024, status)


def clear(paths: Sequence[Path]) -> None:
    """Remove earlier outputs so that every run writes afresh."""
    for path in paths:
        if path.is_dir():
            shutil.rmtree(path)
        else:
            path.unlink(missing_ok=True)
