"""A request's command-line arguments, generated from its declaration, and the request built
back from the parsed arguments."""

from __future__ import annotations

import argparse
import dataclasses
from typing import Any, TypeVar

from .fields import arg_of, request_fields

__all__ = ["add_request_arguments", "request_from_args"]

R = TypeVar("R")


def add_request_arguments(parser: argparse.ArgumentParser, request: type) -> None:
    """One argument per declared field of ``request`` (its ``dest`` is the field's name),
    under its help group's heading when it has one."""
    headings: dict[str, Any] = {}
    groups: dict[str, Any] = {}
    for field in request_fields(request):
        arg = arg_of(field)
        where: Any = parser
        if arg.group:
            if arg.group not in headings:
                headings[arg.group] = parser.add_argument_group(arg.group, arg.group_help or None)
            where = headings[arg.group]
        if arg.exclusive:
            if arg.exclusive not in groups:
                groups[arg.exclusive] = where.add_mutually_exclusive_group()
            where = groups[arg.exclusive]
        kwargs: dict[str, Any] = {"help": arg.help}
        if arg.flags:
            kwargs["dest"] = field.name
        if arg.action == "store_true":
            kwargs["action"] = "store_true"
        elif arg.action == "store_const":
            kwargs.update(action="store_const", const=arg.const)
        else:
            if arg.action != "store":
                kwargs["action"] = arg.action
            for key in ("type", "choices", "metavar", "nargs", "const"):
                if getattr(arg, key) is not None:
                    kwargs[key] = getattr(arg, key)
            if arg.flags and (arg.required or _no_default(field)):
                kwargs["required"] = True
        where.add_argument(*(arg.flags or (field.name,)), **kwargs)


def _no_default(field: dataclasses.Field[Any]) -> bool:
    return field.default is dataclasses.MISSING and \
        field.default_factory is dataclasses.MISSING


def request_from_args(request: type[R], args: argparse.Namespace) -> R:
    """``request`` from parsed arguments: an option not given keeps the field's default;
    lists become tuples. The request's own checks run (:class:`~camlog.errors.RequestError`,
    worded with the flags)."""
    values: dict[str, Any] = {}
    for field in request_fields(request):
        value = getattr(args, field.name, None)
        if value is None or (value is False and arg_of(field).action == "store_true"):
            continue
        values[field.name] = tuple(value) if isinstance(value, list) else value
    return request(**values)
