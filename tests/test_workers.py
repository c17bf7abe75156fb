"""The worker groups of :mod:`tests.workers` reach xdist: a module's tests share a worker."""

from __future__ import annotations

import os

import pytest

from tests.workers import SERVERS


def test_a_module_is_one_group(request: pytest.FixtureRequest) -> None:
    """Under xdist's loadgroup the test's id carries its module's group (xdist schedules by
    it); a pytest whose ids xdist cannot extend fails here, not as a flaky suite."""
    marker = request.node.get_closest_marker("xdist_group")
    assert marker is not None and marker.args == ("tests/test_workers.py",)
    if os.environ.get("PYTEST_XDIST_WORKER") and request.config.getoption("dist") == "loadgroup":
        assert request.node.nodeid.endswith("@tests/test_workers.py"), request.node.nodeid


def test_modules_that_start_one_kind_of_server_share_a_group(request: pytest.FixtureRequest
                                                              ) -> None:
    items = {item.nodeid.split("::", 1)[0]: item for item in request.session.items}
    for modules in SERVERS.values():
        present = [items[m] for m in modules if m in items]
        groups = {item.get_closest_marker("xdist_group").args for item in present}
        assert len(groups) <= 1, (modules, groups)
        missing = [m for m in modules if not (request.config.rootpath / m).is_file()]
        assert not missing, f"tests/workers.py names modules that are gone: {missing}"
