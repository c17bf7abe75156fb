"""The record of a time offset measured between two cameras (``camlog resync
--estimate-offset``'s result file, the resync stats, calibration.json)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..messages import F64
from .base import OMIT_NONE, JsonRecord

__all__ = ["TimeOffset"]


@dataclass(frozen=True)
class TimeOffset(JsonRecord):
    """How much later camera ``second`` stamps an instant than camera ``first``
    (namespaces), measured from their images: ``offset_ms`` with its standard deviation,
    the frames that carried it (where the scene moved) of the frames fitted, the fit's RMS
    residual (px) and the method (``board``: a moving board both see; ``features``: natural
    features of a moving calibrated rig). A frame of ``second`` stamped ``s`` was exposed
    when ``first`` would have stamped ``s - offset_ms``; re-stamping ``second`` by
    ``-offset_ms`` makes the stamps agree. The board method gives the rig it solved,
    ``second_from_first`` (4, 4)."""

    what = "time offset record"

    first: str
    second: str
    offset_ms: float
    std_ms: float
    frames: int
    frames_fitted: int
    rms_px: float
    method: str
    second_from_first: F64 | None = field(default=None, metadata=OMIT_NONE)
