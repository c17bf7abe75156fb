"""The suite on every core (pytest-xdist, ``-n auto --dist loadgroup`` in pyproject.toml):
which tests share a worker.

A test module's tests run on one worker, so that its module-scoped fixtures are made once.
Modules that use a session fixture tagged with :func:`made_once` (a recording of tens of
seconds several modules read) run on one worker together, so that it is made once and not
once per worker; so do the modules of one :data:`SERVERS` kind, which would otherwise race
for ports, displays and Ray's per-machine state. With ``-n 0`` (one process, e.g. under a
debugger) the groups are only markers.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import pytest

from tests.slow import tagged_fixtures

__all__ = ["SERVERS", "group_by_worker", "made_once"]

F = TypeVar("F", bound=Callable[..., Any])

#: modules that start servers of one kind, by kind: Ray clusters and instances, and rerun
#: viewers on virtual X displays
SERVERS = {
    "ray": ("tests/camlog/batch/test_cluster.py", "tests/camlog/batch/test_run.py",
            "tests/benchmarks/test_fleet_check.py"),
    "viewer": ("tests/rerun_export/test_viewer.py", "tests/rerun_export/test_screenshot.py"),
}


def made_once(fixture: F) -> F:
    """Tag a session fixture (under ``@pytest.fixture``) that takes long to make and that
    several modules use: they all run on the worker that makes it."""
    fixture.made_once = True  # type: ignore[attr-defined]
    return fixture


def _module(item: pytest.Item) -> str:
    return item.nodeid.split("::", 1)[0]


def group_by_worker(items: list[pytest.Item]) -> None:
    """Mark every item with the ``xdist_group`` of its module, modules joined when they use
    one :func:`made_once` fixture or start one kind of server."""
    parent: dict[str, str] = {}

    def root(key: str) -> str:
        parent.setdefault(key, key)
        while parent[key] != key:
            parent[key] = parent[parent[key]]
            key = parent[key]
        return key

    def join(a: str, b: str) -> None:
        parent[root(a)] = root(b)

    for kind, modules in SERVERS.items():
        for module in modules:
            join(module, f"servers:{kind}")
    for item in items:
        for name in tagged_fixtures(item, "made_once"):
            join(_module(item), f"fixture:{name}")
    groups: dict[str, str] = {}
    for item in items:
        module = _module(item)
        group = groups.setdefault(module, root(module))
        item.add_marker(pytest.mark.xdist_group(group), append=False)

