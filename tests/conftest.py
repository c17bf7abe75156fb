"""Fixtures shared by every test package, and the fast tier: a test is ``slow`` when it is
marked so or uses a fixture tagged with :func:`tests.slow.renders` (directly or through
other fixtures), so that ``pytest -m "not slow"`` runs only what takes no scene."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.recordings import (  # noqa: F401  (session fixtures: small logs made by the CLI)
    mono_calibration_log,
    red_log,
    red_processed_log,
    resynced_log,
)
from tests.ros_archives import rendered_rig  # noqa: F401  (a session fixture)
from tests.slow import uses_a_slow_fixture
from tests.workers import group_by_worker

REPO_ROOT = Path(__file__).resolve().parents[1]


def _one_thread_per_worker() -> None:
    """When xdist's workers already fill every core, each one (and every process it starts)
    renders and calibrates on one thread: Mesa's llvmpipe and OpenCV would otherwise start a
    pool per process and the pools fight over the same cores (a fifth of the suite's CPU time
    goes to that). The images and numbers are the same on any thread count."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0"))
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
        else os.cpu_count() or 1
    if workers >= cores:
        os.environ.setdefault("LP_NUM_THREADS", "0")  # llvmpipe renders on the calling thread
        os.environ.setdefault("OPENCV_FOR_THREADS_NUM", "1")


_one_thread_per_worker()


#: workers ``-n auto`` starts at most: each renders scenes and starts processes of its own
MAX_WORKERS = 4


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto``: a worker per core this process may run on, at most :data:`MAX_WORKERS`
    (a large machine's count would only start more of them to share the same work)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
        else os.cpu_count() or 1
    return max(1, min(cores, MAX_WORKERS))


@pytest.fixture(scope="session")
def realdata_dir() -> Path:
    """Third-party data folder: ``$CAMLOG_REALDATA`` or ``../shared/realdata`` beside the repo.

    The folder may be absent; tests that need a file in it skip with the path they missed.
    """
    override = os.environ.get("CAMLOG_REALDATA")
    return Path(override) if override else REPO_ROOT.parent / "shared" / "realdata"


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--update-goldens", action="store_true",
                     help="regenerate datasets/golden/expected instead of comparing with it")


@pytest.fixture(scope="session")
def update_goldens(request: pytest.FixtureRequest) -> bool:
    """Whether ``--update-goldens`` asked to regenerate the golden outputs."""
    return bool(request.config.getoption("--update-goldens"))


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark ``slow`` every test that uses a fixture tagged with :func:`tests.slow.renders`,
    and give every test the worker group of :func:`tests.workers.group_by_worker`."""
    for item in items:
        if uses_a_slow_fixture(item):
            item.add_marker(pytest.mark.slow)
    group_by_worker(items)
