"""Typed, checked access to the tables of a scenario spec (TOML)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from replay.messages import F64

from .errors import ScenarioError


class SpecTable:
    """Typed access to one table of a scenario spec, with errors that name the key."""

    def __init__(self, table: Any, where: str, source: str) -> None:
        if not isinstance(table, dict):
            raise ScenarioError(f"{source}: {where} must be a table")
        self.table, self.where, self.source = table, where, source
        self.used: set[str] = set()

    def fail(self, key: str, what: str) -> ScenarioError:
        """The error for a bad value of ``key``."""
        return ScenarioError(f"{self.source}: {self.where}{key}: {what}")

    def get(self, key: str, default: Any = ...) -> Any:
        """The raw value of ``key`` (``default`` when absent; missing is an error)."""
        self.used.add(key)
        if key not in self.table:
            if default is ...:
                raise self.fail(key, "missing")
            return default
        return self.table[key]

    def number(self, key: str, default: Any = ..., *, low: float | None = None,
               high: float | None = None, positive: bool = False) -> float:
        """A finite number, optionally positive or within [low, high]."""
        value = self.get(key, default)
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise self.fail(key, f"expected a number, got {value!r}")
        if positive and value <= 0:
            raise self.fail(key, f"must be > 0, got {value!r}")
        if (low is not None and value < low) or (high is not None and value > high):
            raise self.fail(key, f"must be within [{low}, {high}], got {value!r}")
        return float(value)

    def integer(self, key: str, default: Any = ..., *, low: int = 1) -> int:
        """An integer >= ``low``."""
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise self.fail(key, f"expected an integer >= {low}, got {value!r}")
        return value

    def text(self, key: str, default: Any = ..., *, choices: tuple[str, ...] | None = None) -> str:
        """A non-empty string, optionally one of ``choices``."""
        value = self.get(key, default)
        if not isinstance(value, str) or not value:
            raise self.fail(key, f"expected a non-empty string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.fail(key, f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def vector(self, key: str, n: int | None, default: Any = ...) -> F64:
        """A list of ``n`` numbers (any length when ``n`` is None)."""
        value = self.get(key, default)
        ok = isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        )
        if not ok or (n is not None and len(value) != n):
            size = f"{n} numbers" if n is not None else "a list of numbers"
            raise self.fail(key, f"expected {size}, got {value!r}")
        return np.asarray(value, dtype=np.float64)

    def check_unknown(self) -> None:
        """Raise for the first key of the table that nothing read."""
        unknown = sorted(set(self.table) - self.used)
        if unknown:
            raise self.fail(unknown[0], "unknown key")
