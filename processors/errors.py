"""Exception tree of the processors (image processing, stereo resync)."""

from __future__ import annotations


class ProcessorError(Exception):
    """Base of every error raised by :mod:`processors` and the commands that run them."""


class InputError(ProcessorError):
    """The input log cannot be processed: empty, topic missing, wrong message type."""


class ConfigError(ProcessorError):
    """A processor or resync option is invalid (thresholds, sizes, slop)."""


class FrameError(ProcessorError):
    """One frame could not be processed (undecodable, unsupported encoding, wrong size)."""


class SyncError(ProcessorError):
    """Stereo resync found nothing to pair (no partner within the slop)."""
