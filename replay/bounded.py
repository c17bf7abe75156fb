"""Bounded parsing of structured text (TOML, YAML, JSON): its size and how deeply it nests.

Python's TOML, YAML and JSON parsers recurse once per level of nesting, and so does much of
the code that walks what they return: a file nested a few thousand levels deep would end
them with a ``RecursionError``. Text is measured before it is parsed (brackets outside
strings; YAML's collection events, which its parser makes without recursing) and what was
parsed is measured again (dotted TOML keys and YAML aliases nest without brackets). Every
limit is reported through the caller's own exception class, in one line naming the input.
"""

from __future__ import annotations

import json
import re
import tomllib
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["MAX_DEPTH", "MAX_FILE_BYTES", "MAX_RECORD_BYTES", "check_size", "json_loads",
           "read_text", "reindent_json", "toml_loads", "yaml_load"]

#: levels of nested lists and tables any parsed input may have
MAX_DEPTH = 64
#: size of a configuration file (pipeline, scenario, calibration, manifest)
MAX_FILE_BYTES = 4 << 20
#: size of a JSON record in a log message
MAX_RECORD_BYTES = 64 << 20

Error = Callable[[str], Exception]

_TOML_TOKENS = re.compile(r'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"'
                          r"|'[^'\n]*'|#[^\n]*|[\[\]{}]")
_JSON_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]')


def _megabytes(size: int) -> str:
    return f"{size / (1 << 20):g} MiB" if size >= 1 << 20 else f"{size} bytes"


def read_text(path: Path, error: Error, *, what: str = "", max_bytes: int = MAX_FILE_BYTES,
              missing_hint: str = "") -> str:
    """The text of a local file of at most ``max_bytes``; a missing, unreadable or larger
    one raises ``error`` with one line naming it (``what``, e.g. "pipeline file", first)."""
    named = f"{what} {path}" if what else str(path)
    try:
        with path.open("rb") as file:
            data = file.read(max_bytes + 1)
        if len(data) > max_bytes:
            raise error(f"{named} is larger than {_megabytes(max_bytes)}: refused")
        return data.decode()
    except FileNotFoundError:
        raise error(f"{named} does not exist{missing_hint}") from None
    except (OSError, UnicodeDecodeError) as err:
        raise error(f"cannot read {named}: {err}") from None


def check_size(text: str | bytes, name: str, error: Error, *, max_bytes: int) -> None:
    """Refuse ``text`` longer than ``max_bytes`` (characters for a str)."""
    if len(text) > max_bytes:
        raise error(f"{name} is larger than {_megabytes(max_bytes)}: refused")


def _too_deep(name: str, error: Error) -> Exception:
    return error(f"{name} nests lists or tables more than {MAX_DEPTH} levels deep: refused")


def _check_brackets(text: str, tokens: re.Pattern[str], name: str, error: Error) -> None:
    depth = 0
    for token in tokens.finditer(text):
        mark = token.group()
        if mark in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                raise _too_deep(name, error)
        elif mark in "]}":
            depth = max(0, depth - 1)


def check_depth(value: Any, name: str, error: Error) -> None:
    """Refuse a parsed value whose lists and dicts nest more than :data:`MAX_DEPTH` deep.

    Walks without recursing; a container reached again (a YAML alias) is walked again only
    from a deeper level, so shared parts cost no more than their depth, and a container
    that holds itself is refused as too deep."""
    deepest: dict[int, int] = {}
    stack: list[tuple[Any, int]] = [(value, 1)]
    while stack:
        node, depth = stack.pop()
        if isinstance(node, dict):
            children: Any = node.values()
        elif isinstance(node, list | tuple):
            children = node
        else:
            continue
        if depth > MAX_DEPTH:
            raise _too_deep(name, error)
        if deepest.get(id(node), 0) >= depth:
            continue
        deepest[id(node)] = depth
        stack.extend((child, depth + 1) for child in children)


def toml_loads(text: str, name: str, error: Error, *,
               max_bytes: int = MAX_FILE_BYTES) -> dict[str, Any]:
    """``tomllib.loads`` of bounded text; ``tomllib.TOMLDecodeError`` as from tomllib."""
    check_size(text, name, error, max_bytes=max_bytes)
    _check_brackets(text, _TOML_TOKENS, name, error)
    try:
        value = tomllib.loads(text)
    except RecursionError:
        raise _too_deep(name, error) from None
    check_depth(value, name, error)
    return value


def yaml_load(text: str, name: str, error: Error, *, max_bytes: int = MAX_FILE_BYTES,
              pure: bool = True) -> Any:
    """ruamel's safe load of bounded text; ``YAMLError`` as from ruamel."""
    from ruamel.yaml import YAML
    from ruamel.yaml.events import CollectionEndEvent, CollectionStartEvent

    check_size(text, name, error, max_bytes=max_bytes)
    depth = 0
    for event in YAML(typ="safe", pure=True).parse(text):
        if isinstance(event, CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise _too_deep(name, error)
        elif isinstance(event, CollectionEndEvent):
            depth -= 1
    try:
        value = YAML(typ="safe", pure=pure).load(text)
    except RecursionError:
        raise _too_deep(name, error) from None
    check_depth(value, name, error)
    return value


def json_loads(text: str | bytes, name: str, error: Error, *,
               max_bytes: int = MAX_RECORD_BYTES) -> Any:
    """``json.loads`` of bounded text; ``json.JSONDecodeError`` as from json (JSON nests
    only by brackets, so the text's brackets are all there is to measure)."""
    check_size(text, name, error, max_bytes=max_bytes)
    as_text = text if isinstance(text, str) else bytes(text).decode("utf-8", "replace")
    _check_brackets(as_text, _JSON_TOKENS, name, error)
    try:
        return json.loads(text)
    except RecursionError:
        raise _too_deep(name, error) from None


def reindent_json(text: str, *, indent: int = 1) -> str | None:
    """``text`` as JSON written again with ``indent``; None when it is not JSON within the
    limits."""
    try:
        return json.dumps(json_loads(text, "", ValueError), indent=indent)
    except ValueError:  # json.JSONDecodeError is one
        return None
