"""Moving boards: how much precision a frame loses to motion blur, measured from the data.

A board that moves during the exposure is smeared along its motion; the detector still
finds each corner near its mid-exposure position, but less precisely the faster the board
moves. The solver's residuals show how much: the mean squared residual of a view grows with
the square of the board's speed in the image, ``sigma^2(v) = a + b v^2`` (``v`` in pixels per
frame, the corners' displacement to the nearer neighbouring frame). Fitted to every view, the
law gives each view its weight, ``sqrt(a / (a + b v^2))``, and rejects views whose corners
are more than :data:`BLUR_NOISE_FACTOR` times noisier than a still board's. When the fit
finds no growth, every view keeps weight 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from replay.messages import F64

#: views noisier than this many times a still board's corners are rejected as blurred
BLUR_NOISE_FACTOR = 3.0
#: the growth must stand this many standard errors above zero to count
SIGNIFICANCE = 3.0


@dataclass(frozen=True)
class BlurModel:
    """Corner noise variance per coordinate ``still_var + per_speed2 * v^2`` (px^2) of a
    board moving ``v`` px per frame."""

    still_var: float
    per_speed2: float

    def sigma_px(self, speed_px: F64 | float) -> F64:
        """Corner noise (px per coordinate) at a speed."""
        return np.sqrt(self.still_var + self.per_speed2 * np.square(speed_px))

    def weight(self, speed_px: F64) -> F64:
        """Residual weight of views at these speeds (1 for a still board)."""
        return np.asarray(np.sqrt(self.still_var / (self.still_var + self.per_speed2
                                                    * np.square(speed_px))))

    @property
    def limit_px(self) -> float:
        """Speed (px per frame) beyond which a view is rejected as blurred."""
        return math.sqrt((BLUR_NOISE_FACTOR ** 2 - 1.0) * self.still_var / self.per_speed2)

    def describe(self) -> str:
        """The law in words."""
        return (f"corner noise {math.sqrt(self.still_var):.3f} px on a still board, growing "
                f"as sqrt({self.still_var:.3g} + {self.per_speed2:.3g} v^2) px with the board's "
                f"speed v (px/frame); views beyond {self.limit_px:.1f} px/frame are "
                f"{BLUR_NOISE_FACTOR:g}x noisier and left out")


def fit_blur(speed_px: F64, mean_square_px2: F64, corners: F64) -> BlurModel | None:
    """The blur law from views' speeds ``(V,)``, mean squared residual per coordinate
    ``(V,)`` and inlier corner counts ``(V,)``; None when the views show no growth (or all
    move alike)."""
    keep = np.isfinite(speed_px) & np.isfinite(mean_square_px2) & (corners > 0)
    v2, ms, n = np.square(speed_px[keep]), mean_square_px2[keep], corners[keep]
    if len(v2) < 10 or np.ptp(v2) <= 0:
        return None
    design = np.column_stack([np.ones_like(v2), v2])
    # a view's mean square of 2n squared Gaussians has variance 2 sigma^4 / (2n): weights
    # follow the model's own prediction (iterated twice)
    coefficients = np.linalg.lstsq(design * np.sqrt(n)[:, None], ms * np.sqrt(n), rcond=None)[0]
    for _ in range(2):
        predicted = np.maximum(design @ coefficients, 1e-12)
        w = np.sqrt(n) / predicted
        coefficients, *_ = np.linalg.lstsq(design * w[:, None], ms * w, rcond=None)
    residual = (design @ coefficients - ms) * w
    scale = float(np.sum(residual ** 2)) / max(len(ms) - 2, 1)
    covariance = scale * np.linalg.inv((design * w[:, None]).T @ (design * w[:, None]))
    still, growth = float(coefficients[0]), float(coefficients[1])
    if still <= 0 or growth <= SIGNIFICANCE * math.sqrt(max(covariance[1, 1], 0.0)):
        return None
    return BlurModel(still, growth)
