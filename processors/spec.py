"""What a processor declares about itself: options, outputs and how outputs are displayed.

Declarations are plain data, importable without OpenCV or numpy: the ``process`` command
line, batch pipeline steps and the record ``view`` reads are generated from them, and the
implementation (``module:factory``) is imported only when a processor is built.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from replay.display import Display

from .errors import OptionValueError

__all__ = ["Configured", "Option", "OptionKind", "OutputSpec", "ProcessorSpec"]


class OptionKind(Enum):
    """The type of an option's value."""

    INT = "integer"
    FLOAT = "number"
    TEXT = "text"
    CAMERA_INFO = "camera model"  # a CameraInfo; given as a camera_info_manager YAML path


@dataclass(frozen=True)
class Option:
    """One option: its keyword (the factory's), type, default, help and bounds.

    ``default`` None means "not set" (the processor decides, or it is required).
    ``flag`` is the command-line spelling (default ``--name`` with dashes); ``example`` a
    value as a user would write it (shown in help, used by the registry's tests).
    """

    name: str
    kind: OptionKind
    default: Any
    help: str
    metavar: str = ""
    flag: str = ""
    minimum: float | None = None
    above: float | None = None  # exclusive lower bound
    required: bool = False
    example: str = ""

    @property
    def cli_flag(self) -> str:
        """The command-line flag of this option."""
        return self.flag or "--" + self.name.replace("_", "-")

    def parse_text(self, text: str) -> Any:
        """The value of a command-line word (CAMERA_INFO: the path, as given)."""
        try:
            if self.kind is OptionKind.INT:
                return int(text)
            if self.kind is OptionKind.FLOAT:
                return float(text)
        except ValueError:
            raise ValueError(f"expected {_EXPECTED[self.kind]}, got {text!r}") from None
        return text

    def problem(self, value: Any) -> str | None:
        """Why ``value`` is not acceptable, or None."""
        wrong_type = _type_problem(self.kind, value)
        if wrong_type is not None:
            return wrong_type
        if self.minimum is not None and value < self.minimum:
            return f"must be >= {self.minimum:g}, got {value!r}"
        if self.above is not None and not value > self.above:
            return f"must be > {self.above:g}, got {value!r}"
        return None


def _type_problem(kind: OptionKind, value: Any) -> str | None:
    number = not isinstance(value, bool) and isinstance(value, int | float)
    ok = {
        OptionKind.INT: number and isinstance(value, int),
        OptionKind.FLOAT: number and math.isfinite(value),
        OptionKind.TEXT: isinstance(value, str),
        OptionKind.CAMERA_INFO: type(value).__name__ == "CameraInfo",
    }[kind]
    if ok:
        return None
    if kind is OptionKind.CAMERA_INFO:
        return f"expected a camera model (CameraInfo), got {type(value).__name__}"
    return f"expected {_EXPECTED[kind]}, got {value!r}"


_EXPECTED = {OptionKind.INT: "an integer", OptionKind.FLOAT: "a finite number",
             OptionKind.TEXT: "text"}


@dataclass(frozen=True)
class OutputSpec:
    """One output: its name (the topic's last part), ROS 2 type, display, short title and
    what its message holds (``help``, for the command line).

    ``entity`` is where ``view`` draws it under the camera (a series name for time series);
    empty means ``{processor}/{name}``.
    """

    name: str
    msgtype: str
    display: Display
    label: str
    help: str = ""
    entity: str = ""


@dataclass(frozen=True)
class ProcessorSpec:
    """A processor's declaration.

    A processor is chosen by its flag ``--{name}`` (which takes the ``primary`` option's
    value when it has one), or, without a flag (``flag`` False), by giving any of its
    options. ``selects``: it decides in stream order which frames pass (a throttle) instead
    of computing outputs. ``exclusive`` options may not be given together.
    """

    name: str
    summary: str
    implementation: str  # "module:factory"; the factory takes the options as keywords
    options: tuple[Option, ...] = ()
    outputs: tuple[OutputSpec, ...] = ()
    primary: str = ""
    flag: bool = True
    selects: bool = False
    exclusive: tuple[str, ...] = ()
    title: str = ""  # heading of its options in help

    @property
    def cli_flag(self) -> str:
        """``--red-pixels`` for ``red_pixels``."""
        return "--" + self.name.replace("_", "-")

    def option(self, name: str) -> Option:
        """The option called ``name``."""
        for option in self.options:
            if option.name == name:
                return option
        raise OptionValueError(self.name, (name,), "no such option (options: "
                               f"{', '.join(o.name for o in self.options) or 'none'})")

    def entity(self, output: OutputSpec) -> str:
        """Where ``view`` draws an output under its camera."""
        return output.entity or f"{self.name}/{output.name}"

    def configure(self, values: Mapping[str, Any]) -> Configured:
        """Check ``values`` (option name -> typed value; None: not given) and fill in
        defaults. Raises :class:`OptionValueError` naming the options at fault."""
        given = {name: value for name, value in values.items() if value is not None}
        for name, value in given.items():
            problem = self.option(name).problem(value)
            if problem is not None:
                raise OptionValueError(self.name, (name,), problem)
        clash = [name for name in self.exclusive if name in given]
        if len(clash) > 1:
            raise OptionValueError(self.name, tuple(clash), "give one of them, not several")
        missing = [o.name for o in self.options if o.required and o.name not in given]
        if missing:
            raise OptionValueError(self.name, tuple(missing), "needs a value")
        return Configured(self, {o.name: given.get(o.name, o.default) for o in self.options})


@dataclass(frozen=True)
class Configured:
    """A processor with checked option values, ready to build."""

    spec: ProcessorSpec
    options: Mapping[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        """The processor's name."""
        return self.spec.name

    def build(self) -> Any:
        """The implementation with these options (imported now)."""
        module, _, factory = self.spec.implementation.partition(":")
        return getattr(importlib.import_module(module), factory)(**self.options)

    def described_options(self) -> dict[str, Any]:
        """The option values as JSON values (a camera model by its size and intrinsics)."""
        out: dict[str, Any] = {}
        for name, value in self.options.items():
            if value is None or isinstance(value, bool | int | float | str):
                out[name] = value
            elif type(value).__name__ == "CameraInfo":
                out[name] = {"width": value.width, "height": value.height,
                             "distortion_model": value.distortion_model,
                             "k": [float(v) for v in value.k.reshape(-1)]}
            else:
                out[name] = str(value)
        return out
