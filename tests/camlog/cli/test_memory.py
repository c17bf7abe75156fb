"""Freed buffers are reused: blocks of a few MB allocated and freed again and again
page-fault once, not every time."""

from __future__ import annotations

import platform
import subprocess
import sys

import pytest

SCRIPT = """
import resource, sys
from camlog.cli.memory import keep_freed_memory
if sys.argv[1] == "kept":
    assert keep_freed_memory()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(40):  # three 8 MB blocks at a time, every page written, then freed
    blocks = [b"x" * (8 * 1024 * 1024) for _ in range(3)]
    del blocks
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> int:
    done = subprocess.run([sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True,
                          check=True)
    return int(done.stdout.split()[-1])


@pytest.mark.slow
@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's malloc thresholds")
def test_freed_blocks_are_reused_instead_of_faulted_in_again() -> None:
    pages = 3 * 8 * 1024 * 1024 // 4096  # of one round's blocks
    # the freed heap trimmed, faulted in again: how often depends on what the process freed
    # before (glibc raises its own thresholds after freeing a mapped block; 7 to 27 of the 40
    # rounds' worth here, with and without the modules' bytecode written)
    assert _faults("default") > 5 * pages
    assert _faults("kept") < 3 * pages  # the first round's pages, then reused
