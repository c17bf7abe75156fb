"""Exception tree of the processors (image processing, stereo resync).

Processors never read a log: what is wrong with one (empty, a topic missing, nothing to
pair) is said by the command that reads it, in its own exception tree.
"""

from __future__ import annotations

__all__ = ["ConfigError", "FrameError", "OptionValueError", "ProcessorError", "StampsError"]


class ProcessorError(Exception):
    """Base of every error raised by :mod:`processors` and the commands that run them."""


class StampsError(ProcessorError):
    """Stamps handed to stereo resync are not a sorted 1-D integer array."""


class ConfigError(ProcessorError):
    """A processor or resync option is invalid (thresholds, sizes, slop)."""


class OptionValueError(ConfigError):
    """Options of a processor have values it cannot use.

    Names the processor and its options by their declared names (``edges``, ``low``), never
    by a command-line flag: the command that took the values words the message for its user
    (``--low`` on the command line, ``edges.low`` in a pipeline file).
    """

    def __init__(self, processor: str, options: tuple[str, ...], problem: str) -> None:
        self.processor, self.options, self.problem = processor, options, problem
        super().__init__(f"{processor} {', '.join(options)}: {problem}" if options
                         else f"{processor}: {problem}")


class FrameError(ProcessorError):
    """One frame could not be processed (undecodable, unsupported encoding, wrong size)."""
