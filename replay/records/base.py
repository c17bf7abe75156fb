"""JSON records that read and write themselves: dataclasses <-> JSON objects, checked on read.

A record is a dataclass whose fields are JSON values (``int``, ``float``, ``str``, ``bool``,
``Any``), numpy arrays (``F64``: nested lists of numbers), other records, or ``list``,
``tuple`` or ``dict[str, ...]`` of those, optionally ``| None``. A field whose metadata says
``omit_none`` is left out of the JSON object when it is None (and is None when absent);
keys appear in field order. Keys a record does not know are ignored on read, so that older
camlog versions read newer records.
"""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from collections.abc import Callable
from typing import Any, ClassVar, Self, TypeVar, Union

import numpy as np

from ..bounded import json_loads
from ..errors import RecordError
from ..messages import Text

__all__ = ["OMIT_NONE", "JsonRecord", "from_json", "to_json"]

#: field metadata: leave the key out of the JSON object when the value is None
OMIT_NONE: dict[str, Any] = {"omit_none": True}

T = TypeVar("T")


def to_json(value: Any) -> Any:
    """The JSON value of a record, array or container (records recursively)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        custom = getattr(value, "json_value", None)
        if custom is not None:
            return custom()
        out: dict[str, Any] = {}
        for f in dataclasses.fields(value):
            item = getattr(value, f.name)
            if item is None and f.metadata.get("omit_none"):
                continue
            out[f.name] = to_json(item)
        return out
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [to_json(v) for v in value]
    return value


def _fail(where: str, expected: str, value: Any) -> RecordError:
    shown = json.dumps(value)[:40] if _jsonable(value) else type(value).__name__
    return RecordError(f"{where}: expected {expected}, got {shown}")


def _jsonable(value: Any) -> bool:
    try:
        json.dumps(value)
    except (TypeError, ValueError):
        return False
    return True


def _array(_args: tuple[Any, ...], value: Any, where: str) -> Any:
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise _fail(where, "an array of numbers", value) from None


def _list(args: tuple[Any, ...], value: Any, where: str) -> Any:
    if not isinstance(value, list):
        raise _fail(where, "a list", value)
    return [_read(args[0], v, f"{where}[{i}]") for i, v in enumerate(value)]


def _tuple(args: tuple[Any, ...], value: Any, where: str) -> Any:
    if not isinstance(value, list):
        raise _fail(where, "a list", value)
    hints = [args[0]] * len(value) if len(args) == 2 and args[1] is Ellipsis else list(args)
    if len(value) != len(hints):
        raise _fail(where, f"{len(hints)} values", value)
    return tuple(_read(h, v, f"{where}[{i}]") for i, (h, v) in enumerate(zip(hints, value,
                                                                            strict=True)))


def _dict(args: tuple[Any, ...], value: Any, where: str) -> Any:
    if not isinstance(value, dict):
        raise _fail(where, "an object", value)
    return {k: _read(args[1], v, f"{where}.{k}") for k, v in value.items()}


#: container type -> reader of (type arguments, JSON value, where)
_CONTAINERS: dict[Any, Callable[[tuple[Any, ...], Any, str], Any]] = {
    np.ndarray: _array, list: _list, tuple: _tuple, dict: _dict,
}
#: scalar type -> (accepts the JSON value, what was expected)
_SCALARS: dict[Any, tuple[Callable[[Any], bool], str]] = {
    bool: (lambda v: isinstance(v, bool), "true or false"),
    int: (lambda v: isinstance(v, int) and not isinstance(v, bool), "an integer"),
    float: (lambda v: isinstance(v, int | float) and not isinstance(v, bool), "a number"),
    str: (lambda v: isinstance(v, str), "a string"),
}


def _read(hint: Any, value: Any, where: str) -> Any:
    """``value`` (parsed JSON) as the type ``hint``; RecordError says where it does not fit."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if origin in (Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        (hint,) = [a for a in args if a is not type(None)]
        origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return value
    if dataclasses.is_dataclass(hint):
        return from_json(typing.cast(type[Any], hint), value, where)
    container = _CONTAINERS.get(origin or hint)
    if container is not None:
        return container(args, value, where)
    if hint not in _SCALARS:
        raise TypeError(f"{where}: records cannot hold {hint!r}")
    accepts, expected = _SCALARS[hint]
    if not accepts(value):
        raise _fail(where, expected, value)
    return float(value) if hint is float else value


def from_json(cls: type[T], data: Any, where: str = "") -> T:
    """A record of type ``cls`` from its JSON object (``where`` prefixes error messages)."""
    custom = getattr(cls, "from_json_value", None)
    if custom is not None:
        return typing.cast(T, custom(data, where))
    if not isinstance(data, dict):
        raise _fail(where or cls.__name__, "an object", data)
    if not dataclasses.is_dataclass(cls):
        raise TypeError(f"{cls!r} is not a record (a dataclass)")
    hints = typing.get_type_hints(cls)
    values: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        key = f"{where}.{f.name}" if where else f.name
        if f.name not in data:
            if f.metadata.get("omit_none"):
                values[f.name] = None
                continue
            if f.default is not dataclasses.MISSING or \
                    f.default_factory is not dataclasses.MISSING:
                continue
            raise RecordError(f"{key}: missing")
        values[f.name] = _read(hints[f.name], data[f.name], key)
    return cls(**values)


class JsonRecord:
    """Mixin for a record stored as JSON in a ``std_msgs/String`` message."""

    #: the record's name in error messages
    what: ClassVar[str] = "record"

    def to_json_text(self, *, indent: int | None = None) -> str:
        """The record as JSON text."""
        return json.dumps(to_json(self), indent=indent)

    def to_message(self, *, indent: int | None = None) -> Text:
        """The record as a ``std_msgs/String`` message."""
        return Text(self.to_json_text(indent=indent))

    @classmethod
    def from_json_text(cls, text: str) -> Self:
        """Parse the record from JSON text; RecordError when it is not one."""
        try:
            data = json_loads(text, cls.what, RecordError)
        except json.JSONDecodeError as err:
            raise RecordError(f"{cls.what}: not valid JSON ({err.msg} at line {err.lineno})") \
                from None
        try:
            return from_json(cls, data)
        except RecordError as err:
            raise RecordError(f"{cls.what}: {err}") from None

    @classmethod
    def from_message(cls, message: object) -> Self:
        """Parse the record from a ``std_msgs/String`` message."""
        if not isinstance(message, Text):
            raise RecordError(f"{cls.what}: expected a std_msgs/String message, got "
                              f"{type(message).__name__}")
        return cls.from_json_text(message.data)
