"""Exception tree of the log layer."""

from __future__ import annotations


class ReplayError(Exception):
    """Base of every error raised by :mod:`replay`."""


class LogFormatError(ReplayError):
    """The path does not name a log in a known format, or the format is not supported."""


class LogReadError(ReplayError):
    """A log could not be read (missing, corrupt, truncated)."""


class OutputError(ReplayError):
    """An output cannot be written where asked (exists, is an input, unwritable folder)."""


class LogWriteError(OutputError):
    """A log could not be written (exists, unwritable, bad message)."""


class EncodingError(ReplayError):
    """An image encoding is not supported or the pixel buffer does not match it."""


class UnsupportedEncodingError(EncodingError):
    """A whole stream's encoding or format is not supported (not one broken frame)."""


class TopicError(ReplayError):
    """A requested topic does not exist in a log or has the wrong type."""


class OptionError(ReplayError):
    """Options are out of range or contradict each other (e.g. ``--start`` after ``--end``)."""


class ImageFolderError(ReplayError):
    """A folder of image files cannot be imported (missing, empty, unreadable, mixed sizes)."""


class RecordError(ReplayError):
    """A well-known JSON record (scenario, calibration summary, residuals...) is malformed."""


class StorageError(ReplayError):
    """A log location (object storage, URI) cannot be reached, listed, read or written."""
