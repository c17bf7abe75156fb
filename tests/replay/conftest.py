"""Fixtures of the log-layer tests."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from .samples import OUTPUT_NAMES, Entry, every_kind


@pytest.fixture
def sample_entries() -> list[Entry]:
    """``(topic, log_time_ns, message)`` covering every message kind and image encoding."""
    return every_kind()


@pytest.fixture
def log_path(tmp_path: Path) -> Callable[[str], Path]:
    """Output path for a writer format name, inside the test's temporary directory."""

    def path_for(fmt: str) -> Path:
        return tmp_path / OUTPUT_NAMES[fmt]

    return path_for
