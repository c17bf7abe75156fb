"""Pure image processors and stereo pairing over camlog's typed messages.

Processors map an :class:`replay.Image` to output messages and never open files; the
``camlog process`` / ``camlog resync`` commands stream logs through them.
"""

from .base import Output, Processor
from .errors import ConfigError, FrameError, InputError, ProcessorError, SyncError
from .registry import PROCESSORS, make_processor

__all__ = [
    "PROCESSORS",
    "ConfigError",
    "FrameError",
    "InputError",
    "Output",
    "Processor",
    "ProcessorError",
    "SyncError",
    "make_processor",
]
