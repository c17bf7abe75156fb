"""Recordings shared by the recorder tests: each is rendered once per test session."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.slow import renders

from .logs import Log, record_log

#: a spec name or path plus sorted overrides -> its recording
RecordingKey = tuple[str, tuple[tuple[str, Any], ...]]


@pytest.fixture(scope="session")
@renders
def recording(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., Log]:
    """``recording(scenario, **overrides)``: a cached MCAP recording, read back."""
    cache: dict[RecordingKey, Log] = {}

    def get(scenario: str | Path, **overrides: Any) -> Log:
        key = (str(scenario), tuple(sorted((k, _hashable(v)) for k, v in overrides.items())))
        if key not in cache:
            path = tmp_path_factory.mktemp("recording") / "log.mcap"
            cache[key] = record_log(scenario, path, **overrides)
        return cache[key]

    return get


def _hashable(value: Any) -> Any:
    if isinstance(value, dict):
        return tuple(sorted((k, _hashable(v)) for k, v in value.items()))
    return tuple(_hashable(v) for v in value) if isinstance(value, list) else value
