"""A request built from a pipeline step's table (TOML/YAML values), validated with the same
value types as the command line; every error is one line naming the step and the key."""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping
from typing import Any, TypeVar

from ..errors import PipelineError
from .fields import Arg, RequestError, arg_of, batch_keys, request_fields

__all__ = ["keyed", "request_from_table", "table_value"]

R = TypeVar("R")

#: actions whose option takes several values (a pipeline gives one value or a list)
LISTS = ("append", "extend")


def table_value(arg: Arg, value: Any) -> Any:
    """The typed value of a pipeline value for an option declared by ``arg``; raises
    :class:`ValueError` with the reason."""
    if arg.action in ("store_true", "store_const"):
        if not isinstance(value, bool):
            raise ValueError(f"expected true or false, got {value!r}")
        return value
    if arg.action in LISTS or arg.nargs in ("+", "*"):
        items = value if isinstance(value, list) else [value]
        if not items:
            raise ValueError("expected a value or a non-empty list")
        return tuple(_one(arg, item) for item in items)
    typed = _one(arg, value)
    return tuple(typed) if isinstance(typed, list) else typed


def _one(arg: Arg, value: Any) -> Any:
    if isinstance(value, bool | list | dict) or value is None:
        raise ValueError(f"expected {'a number or text' if arg.type else 'text'}, got {value!r}")
    if arg.type is None and not isinstance(value, str):
        raise ValueError(f"expected text, got {value!r}")
    try:
        typed = arg.type(str(value)) if arg.type is not None else value
    except (argparse.ArgumentTypeError, ValueError) as err:
        raise ValueError(str(err) or f"invalid value {value!r}") from None
    if arg.choices is not None and typed not in arg.choices:
        raise ValueError(f"expected one of {', '.join(arg.choices)}, got {value!r}")
    return typed


def request_from_table(request: type[R], table: Mapping[str, Any], *, step: str,
                       **given: Any) -> R:
    """``request`` from a step's ``table`` (key = field name) and what the runner ``given``
    (input, output, overwrite, progress). Errors: :class:`PipelineError` ``STEP: KEY: ...``.
    """
    allowed = batch_keys(request)
    fields = {f.name: f for f in request_fields(request)}
    values: dict[str, Any] = {}
    for key, value in table.items():
        if key not in allowed:
            raise PipelineError(f"{step}: no option {key!r} (options: "
                                f"{', '.join(sorted(allowed)) or 'none'})")
        try:
            values[key] = table_value(arg_of(fields[key]), value)
        except ValueError as err:
            raise PipelineError(f"{step}: {key}: {err}") from None
    missing = [name for name in sorted(allowed) if name not in values
               and fields[name].default is dataclasses.MISSING]
    if missing:
        raise PipelineError(f"{step}: give {' and '.join(missing)}")
    try:
        return request(**values, **given)
    except RequestError as err:
        raise PipelineError(f"{step}: {keyed(err)}") from None


def keyed(err: RequestError) -> str:
    """A request's error worded with pipeline keys (the field names)."""
    return err.worded({f.name: f.name for f in request_fields(err.request)})
