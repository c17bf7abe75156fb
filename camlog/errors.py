"""Exception tree of the camlog application; the CLI prints any of them as one line."""

from __future__ import annotations

__all__ = ["CalibrationError", "CamlogError", "ClusterError", "GoldenError", "InputError",
           "PipelineError", "ProcessingError", "SyncError",
           "UsageError"]


class CamlogError(Exception):
    """Base of every error raised by :mod:`camlog` itself."""


class InputError(CamlogError):
    """An input (log, calibration file, folder) does not hold what the command needs."""


class UsageError(CamlogError):
    """Options are missing, out of range or contradict each other."""


class CalibrationError(CamlogError):
    """The views of a log do not allow a calibration (no board, no pairs)."""


class ProcessingError(CamlogError):
    """A processor failed on one frame of a log."""


class SyncError(CamlogError):
    """Stereo resync found nothing to pair."""


class PipelineError(CamlogError):
    """A batch pipeline file or one of its steps is invalid."""


class ClusterError(CamlogError):
    """A Ray cluster cannot be reached, or one of its nodes cannot run camlog."""


class GoldenError(CamlogError):
    """The golden inputs do not match their manifest, or a golden job cannot run."""
