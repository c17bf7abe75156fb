"""Logs shared by the batch fault tests: recorded once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from .faults import record_logs
from .test_run import PIPELINE


@pytest.fixture(scope="session")
def short_logs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Six short stereo_unsynced logs (40 frames per camera, 160x120), ``pipe.toml`` (the
    resync, process, info pipeline) next to them."""
    tmp = tmp_path_factory.mktemp("short_logs")
    (tmp / "pipe.toml").write_text(PIPELINE)
    return record_logs(tmp, 6, 40)
