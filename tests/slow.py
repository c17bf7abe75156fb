"""The fast tier's rule: a fixture that renders a scene (or runs a job of seconds) is tagged
with :func:`renders`, and every test that uses it is slow, as are the tests marked
``@pytest.mark.slow`` (rendering in their body, starting processes, benchmark-like)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import pytest

__all__ = ["renders", "tagged_fixtures", "uses_a_slow_fixture"]

F = TypeVar("F", bound=Callable[..., Any])


def renders(fixture: F) -> F:
    """Tag a fixture (under ``@pytest.fixture``) whose set-up renders a scene or runs a job
    of seconds: the tests that use it are slow."""
    fixture.slow = True  # type: ignore[attr-defined]
    return fixture


def tagged_fixtures(item: pytest.Item, tag: str) -> list[str]:
    """The fixtures ``item`` uses, directly or through others, whose function carries the
    attribute ``tag`` (set by a decorator such as :func:`renders`)."""
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return []
    # the last definition of a name is the one the test gets (a module's overrides a
    # conftest's)
    return [name for name in getattr(item, "fixturenames", ())
            if (definitions := info.name2fixturedefs.get(name))
            and getattr(definitions[-1].func, tag, False)]


def uses_a_slow_fixture(item: pytest.Item) -> bool:
    """Whether a tagged fixture is among those ``item`` uses, directly or through others."""
    return bool(tagged_fixtures(item, "slow"))
