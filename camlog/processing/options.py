"""Processor options as users give them (command-line words, pipeline values) made typed.

This is the edge where a calibration file named by an option is read: processors receive
the camera model, never a path.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from processors.errors import OptionValueError
from processors.spec import Configured, Option, OptionKind, ProcessorSpec

__all__ = ["configure_values", "resolve_value"]


def resolve_value(spec: ProcessorSpec, option: Option, value: Any) -> Any:
    """The typed value of ``option`` given as text, a number or a path (None stays None)."""
    if value is None:
        return None
    if option.kind is OptionKind.CAMERA_INFO and isinstance(value, str | Path):
        from replay.calibration_yaml import load_calibration

        return load_calibration(Path(value)).camera_info
    if isinstance(value, str) and option.kind in (OptionKind.INT, OptionKind.FLOAT):
        try:
            return option.parse_text(value)
        except ValueError as err:
            raise OptionValueError(spec.name, (option.name,), str(err)) from None
    if option.kind is OptionKind.FLOAT and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def configure_values(spec: ProcessorSpec, values: Mapping[str, Any]) -> Configured:
    """``spec`` configured from user values (option name -> text, number, path or None)."""
    typed = {name: resolve_value(spec, spec.option(name), value)
             for name, value in values.items()}
    return spec.configure(typed)
