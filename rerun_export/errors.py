"""Exception tree of the rerun export."""

from __future__ import annotations

__all__ = ["RerunExportError", "ViewerError"]


class RerunExportError(Exception):
    """Base of every error raised by :mod:`rerun_export`."""


class ViewerError(RerunExportError):
    """A rerun recording could not be written or a viewer could not be reached."""
