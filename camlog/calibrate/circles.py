"""The diameter of a circle grid's circles: given, or measured in the views."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from processors.calibration.board import Board

from ..errors import CalibrationError
from .views import CameraViews

#: a given circle diameter this far (relative) from the measured one earns a warning
DIAMETER_WARNING = 0.05

__all__ = ["DIAMETER_WARNING", "CircleSize", "circle_size"]


@dataclass(frozen=True)
class CircleSize:
    """The diameter of a circle grid's circles the solve used: given, or ``measured`` in the
    views (``measured_m``: the median over the candidate views, None when none measured)."""

    diameter_m: float
    measured: bool
    measured_m: float | None

    def describe(self) -> str:
        """The diameter and where it came from, e.g. ``0.01000 m (measured from the
        images)``."""
        if self.measured:
            return f"{self.diameter_m:.5f} m (measured from the images)"
        seen = f"; the images show {self.measured_m:.5f} m" if self.measured_m else ""
        return f"{self.diameter_m:.5f} m (given{seen})"

    def warning(self) -> str | None:
        """What the user should know when the given diameter is not what the images show."""
        if self.measured or self.measured_m is None or \
                abs(self.diameter_m / self.measured_m - 1) <= DIAMETER_WARNING:
            return None
        return (f"--diameter {self.diameter_m:g} m, but the images show circles "
                f"{self.measured_m:.5f} m across")


def circle_size(cameras: list[CameraViews], board: Board,
                diameter_m: float | None) -> CircleSize | None:
    """The circles' diameter: ``diameter_m`` when given, else the median of what the
    candidate views measured; None when the board is not a circle grid."""
    if not board.circle_grid:
        return None
    seen = [f.detection.diameter_m for c in cameras for f in c.frames
            if f.candidate and f.detection is not None and f.detection.diameter_m is not None]
    measured_m = float(np.median(seen)) if seen else None
    if diameter_m is not None:
        return CircleSize(diameter_m, False, measured_m)
    if measured_m is None:
        raise CalibrationError("the circles' diameter could not be measured in any view: "
                               "give it with --diameter")
    if not 0 < measured_m < board.nearest_m:
        raise CalibrationError(f"the images show circles {measured_m:.5f} m across, which "
                               f"would overlap at a spacing of {board.square_m:g} m: check "
                               "--square, or give --diameter")
    return CircleSize(measured_m, True, measured_m)
