"""Logs shared by the batch fault tests: recorded once per session; a home of their own.

Ray writes into the user's home (``~/.ray/auth_token``, the token a local instance makes
for itself, which a later ``ray start --head`` then enforces) and under ``/tmp/ray``: every
batch test, and whatever it starts, runs with HOME and RAY_TMPDIR in a temporary folder.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.slow import renders
from tests.workers import made_once

from .faults import record_logs
from .test_run import PIPELINE


@pytest.fixture(scope="package", autouse=True)
def temporary_home() -> Iterator[Path]:
    """HOME and RAY_TMPDIR of the batch tests (short: Ray's socket paths are limited)."""
    home = Path(tempfile.mkdtemp(prefix="rh", dir="/tmp"))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("HOME", str(home))
        patch.setenv("RAY_TMPDIR", str(home / "tmp"))
        yield home
    shutil.rmtree(home, ignore_errors=True)


@pytest.fixture(scope="session")
@renders
@made_once
def short_logs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Six short stereo_unsynced logs (40 frames per camera, 160x120), ``pipe.toml`` (the
    resync, process, info pipeline) next to them."""
    tmp = tmp_path_factory.mktemp("short_logs")
    (tmp / "pipe.toml").write_text(PIPELINE)
    return record_logs(tmp, 6, 40)
