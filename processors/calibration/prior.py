"""A weak prior on the distortion coefficients: the choices the corners leave free.

One residual per coefficient, ``weight * value`` pixels, added to the corners' residuals (a
Gaussian prior centred on zero; the covariance of :mod:`.normal` includes it).

**The radial terms.** The radial factor 1 + k1 r^2 + k2 r^4 + k3 r^6 is a polynomial the
corners sample only up to the radius the boards reach. Over those radii r^2, r^4 and r^6 are
nearly collinear, so the corners hold one combination of k1 k2 k3 and leave the others free:
through a narrow lens (r < 0.4 at the image corners) the views fit k3 = -0.6 as well as the
true -0.018, k1 and k2 absorbing the difference within the corners, and beyond them, in the
image corners the boards never reach, the solutions part by most of a pixel. The prior
(:data:`RADIAL_PRIOR_PX` pixels per unit of k1, k2 and k3) is stated in units of the
coefficients, not of the pixels they move: a higher-order term moves far fewer pixels within
the corners per unit than a lower one, so it costs more per pixel explained, and of the
solutions the corners cannot tell apart the prior picks the one that explains the distortion
with the low orders, using a high order only as far as the corners demand it. At 0.3 px per
unit a coefficient of 0.1 weighs as much as one corner 0.03 px off: for corners measured to
0.05 px a prior width of about 0.17, the size of real lenses' k2 and k3 and nothing beside
thousands of corners where they decide (views that span a wide lens's image hold its k3 to
1e-4, and the prior moves it by under a hundredth of that). mrcal regularises every distortion
coefficient the same way, at 0.1 px per unit; three times that is what holds k3 of the
vs_mrcal moving board through a k3 lens (13 seeds, k1 k2 p1 p2 k3 fitted: k3 -0.61 median
without the prior, -0.37 at 0.1 px per unit, -0.09 at 0.3, truth -0.018; the max projection
difference over the image 0.183, 0.095 and 0.033 px).

**The rational model's denominator.** (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 +
k6 r^6) is nearly unchanged when numerator and denominator gain the same factor (1 + a r^2):
the corners cannot tell such solutions apart, and they part only beyond the corners. The
prior on k4 k5 k6 (:data:`DENOMINATOR_PRIOR_PX` per unit, stronger: nothing in a real lens
calls for a large denominator) picks the solution with the smallest denominator (mrcal
weighs its denominators five times its other coefficients likewise).

The fisheye model is left without a prior: its boards reach the image's edge, and the
weights were not measured on it.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from replay.lens_models import LENS_MODELS
from replay.messages import F64

#: the rational model's denominator coefficients, held near zero by the prior
RATIONAL_DENOMINATOR = ("k4", "k5", "k6")
#: residual (px) per unit of each denominator coefficient
DENOMINATOR_PRIOR_PX = 1.0
#: the radial coefficients of plumb_bob and of the rational model's numerator
RADIAL = ("k1", "k2", "k3")
#: residual (px) per unit of each radial coefficient
RADIAL_PRIOR_PX = 0.3


def weights(models: list[str], names: list[list[str]],
            columns: list[npt.NDArray[np.int64]], count: int) -> F64:
    """``(count,)`` the prior's pixels per unit of each unknown (0: no prior), from each
    camera's distortion model, the names of its free intrinsics and their columns."""
    out = np.zeros(count)
    for model, labels, where in zip(models, names, columns, strict=True):
        if LENS_MODELS[model].fisheye:  # the prior holds pinhole lenses' coefficients
            continue
        for label, column in zip(labels, where, strict=True):
            if label in RADIAL:
                out[column] = RADIAL_PRIOR_PX
            elif model == "rational_polynomial" and label in RATIONAL_DENOMINATOR:
                out[column] = DENOMINATOR_PRIOR_PX
    return out
