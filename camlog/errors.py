"""Exception tree of the camlog application; the CLI prints any of them as one line."""

from __future__ import annotations

__all__ = ["CalibrationError", "CamlogError", "ClusterError", "GoldenError", "InputError",
           "PipelineError", "ProcessingError", "RequestError", "SyncError",
           "UsageError"]


class CamlogError(Exception):
    """Base of every error raised by :mod:`camlog` itself."""


class InputError(CamlogError):
    """An input (log, calibration file, folder) does not hold what the command needs."""


class UsageError(CamlogError):
    """Options are missing, out of range or contradict each other."""


class RequestError(UsageError):
    """A command's request is invalid: ``template`` names its options as ``{field}``, which
    read as flags (``--left``) on the command line and as keys (``left``) in a pipeline."""

    def __init__(self, request: type, template: str) -> None:
        self.request = request
        self.template = template
        super().__init__(template)

    def worded(self, word: dict[str, str]) -> str:
        """The message with each ``{field}`` given as ``word[field]``."""
        return self.template.format_map(word)

    def __str__(self) -> str:
        from .requests.fields import flag_words

        return self.worded(flag_words(self.request))


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
