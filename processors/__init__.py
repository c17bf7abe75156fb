"""Pure image processors and stereo pairing over camlog's typed messages.

Processors map an :class:`replay.Image` to output messages and never open files; the
``camlog process`` / ``camlog resync`` commands stream logs through them. Their
declarations (:mod:`processors.registry`) load no numerical library.
"""

from .base import Output, Processor
from .errors import (
    ConfigError,
    FrameError,
    OptionValueError,
    ProcessorError,
    StampsError,
)
from .registry import PROCESSORS, configure, make_processor
from .spec import Configured, Option, OptionKind, OutputSpec, ProcessorSpec

__all__ = [
    "PROCESSORS",
    "ConfigError",
    "Configured",
    "FrameError",
    "Option",
    "OptionKind",
    "OptionValueError",
    "Output",
    "OutputSpec",
    "Processor",
    "ProcessorError",
    "ProcessorSpec",
    "StampsError",
    "configure",
    "make_processor",
]
