"""A request built from a pipeline step's table (TOML/YAML values), validated with the same
value types as the command line; every error is one line naming the step and the key."""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Mapping
from typing import Any, TypeVar

from ..errors import PipelineError
from .fields import Arg, RequestError, arg_of, batch_keys, key_of, request_fields

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
    """``request`` from a step's ``table`` (keys: :func:`~.fields.key_of`; a table value
    gives the keys of a table, ``edges = {low = 40}``) and what the runner ``given`` (input,
    output, overwrite, progress). Errors: :class:`PipelineError` ``STEP: KEY: ...``.
    """
    allowed = batch_keys(request)
    fields = {key_of(f): f for f in request_fields(request) if arg_of(f).batch}
    values: dict[str, Any] = {}
    for key, value in table.items():
        if key not in allowed:
            raise PipelineError(f"{step}: no option {key!r} (options: "
                                f"{', '.join(sorted(allowed)) or 'none'})")
        inner = sorted(k.partition(".")[2] for k in fields if k.startswith(f"{key}."))
        if inner and isinstance(value, dict):
            values[fields[key].name] = True
            for sub, item in value.items():
                if sub not in inner:
                    raise PipelineError(f"{step}: {key}.{sub}: no such option (options: "
                                        f"{', '.join(inner)})")
                values[fields[f"{key}.{sub}"].name] = _value(fields[f"{key}.{sub}"], item,
                                                              f"{step}: {key}.{sub}")
        elif inner and not isinstance(value, bool):
            raise PipelineError(f"{step}: {key}: expected true, false or a table of its "
                                f"options ({', '.join(inner)}), got {value!r}")
        else:
            values[fields[key].name] = _value(fields[key], value, f"{step}: {key}")
    missing = [key for key in sorted(allowed) if fields[key].name not in values
               and fields[key].default is dataclasses.MISSING]
    if missing:
        raise PipelineError(f"{step}: give {' and '.join(missing)}")
    try:
        return request(**values, **given)
    except RequestError as err:
        raise PipelineError(f"{step}: {keyed(err)}") from None


def _value(field: dataclasses.Field[Any], value: Any, where: str) -> Any:
    try:
        return table_value(arg_of(field), value)
    except ValueError as err:
        raise PipelineError(f"{where}: {err}") from None


def keyed(err: RequestError) -> str:
    """A request's error worded with pipeline keys (the field names)."""
    return err.worded({f.name: key_of(f) for f in request_fields(err.request)})
