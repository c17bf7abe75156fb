"""Fixtures shared by every test package."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def realdata_dir() -> Path:
    """Third-party data folder: ``$CAMLOG_REALDATA`` or ``../shared/realdata`` beside the repo.

    The folder may be absent; tests that need a file in it skip with the path they missed.
    """
    override = os.environ.get("CAMLOG_REALDATA")
    return Path(override) if override else REPO_ROOT.parent / "shared" / "realdata"
