"""A prior on the rational model's denominator.

The rational model's radial factor (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 +
k6 r^6) is nearly unchanged when numerator and denominator gain the same factor (1 + a r^2):
the corners cannot tell such solutions apart, and they part only beyond the corners, in the
image corners. A prior (one residual per denominator coefficient, :data:`DENOMINATOR_PRIOR_PX`
pixels per unit) picks the solution with the smallest denominator: it weighs as much as one
corner 0.1 px off for a coefficient of 0.1, nothing beside thousands of corners wherever they
decide, and it decides the trade they leave free (mrcal regularises its models likewise).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from replay.messages import F64

#: the rational model's denominator coefficients, held near zero by the prior
RATIONAL_DENOMINATOR = ("k4", "k5", "k6")
#: residual (px) per unit of each denominator coefficient
DENOMINATOR_PRIOR_PX = 1.0


def weights(models: list[str], names: list[list[str]],
            columns: list[npt.NDArray[np.int64]], count: int) -> F64:
    """``(count,)`` the prior's pixels per unit of each unknown (0: no prior), from each
    camera's distortion model, the names of its free intrinsics and their columns."""
    out = np.zeros(count)
    for model, labels, where in zip(models, names, columns, strict=True):
        if model == "rational_polynomial":
            for label, column in zip(labels, where, strict=True):
                if label in RATIONAL_DENOMINATOR:
                    out[column] = DENOMINATOR_PRIOR_PX
    return out
