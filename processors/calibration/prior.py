"""A weak prior on the distortion coefficients: the choices the corners leave free.

One residual per coefficient, ``weight * value`` pixels, added to the corners' residuals (a
Gaussian prior centred on zero; the covariance of :mod:`.normal` includes it).

**The radial terms.** The radial factor 1 + k1 r^2 + k2 r^4 + k3 r^6 is a polynomial the
corners sample only up to the radius the boards reach. Over those radii r^2, r^4 and r^6 are
nearly collinear, so the corners hold one combination of k1 k2 k3 and leave the others free:
through a narrow lens (r < 0.4 at the image corners) the views fit k3 = -0.6 as well as the
true -0.018, k1 and k2 absorbing the difference within the corners, and beyond them, in the
image corners the boards never reach, the solutions part by most of a pixel. The prior is
stated in units of the coefficients, not of the pixels they move: a higher-order term moves far
fewer pixels within the corners per unit than a lower one, so it costs more per pixel
explained, and of the solutions the corners cannot tell apart the prior picks the one that
explains the distortion with the low orders, using a high order only as far as the corners
demand it.

**Its weight.** As mrcal 2.5 weighs its regularisation: the prior's cost, were every coefficient
of the model :data:`NOMINAL_COEFFICIENT`, is :data:`PRIOR_SHARE` of the corners' cost were each
1 px off (:func:`coefficient_px`), so it grows with the square root of the corners seen: 0.56 px
per unit for 30 views of a 7x6 board, 1.8 px for 300 frames of a waved one. The corners'
information on the combinations they hold grows with their count too, so the prior keeps the
same small share of every solve (views that span a wide lens's image hold its k3 to 1e-4, and
the prior moves it by well under a tenth of its sigma), and decides only what the corners leave
free. On vs_mrcal's moving board through a k3 lens (k1 k2 p1 p2 k3 fitted, 11 seeds, median max
projection difference over the image) a fixed 0.3 px per unit gave 0.033 px, 1 px 0.040 px, this
rule 0.023 px and mrcal 0.027 px; without a prior k3 runs to -0.6 and the image corners are 0.18
px off (13 seeds). The prior's pull is a bias where the views leave a coefficient free: on 80
synthetic views over the middle 40 % of a narrow lens's image it leaves the image corners 0.19
px off (0.08 at a fixed 0.3 px per unit, 1.3 px without a prior). The pull is not knowledge of
the lens: the stated uncertainty propagates the prior at no more than :data:`STATED_RADIAL_PX`
(:func:`stated_weights`, used by :attr:`.robust.Problem.stated_normal`), so a coefficient the
views leave free keeps the width real lenses give it.

**The rational model's denominator.** (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 +
k6 r^6) is nearly unchanged when numerator and denominator gain the same factor (1 + a r^2):
the corners cannot tell such solutions apart, and they part only beyond the corners. The
prior on k4 k5 k6 (:data:`DENOMINATOR_FACTOR` times the numerator's: nothing in a real lens
calls for a large denominator) picks the solution with the smallest denominator, as mrcal
weighs its denominators.

The fisheye model is left without a prior: its boards reach the image's edge, and the
weights were not measured on it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from replay.lens_models import LENS_MODELS
from replay.messages import F64

#: the rational model's denominator coefficients, held near zero by the prior
RATIONAL_DENOMINATOR = ("k4", "k5", "k6")
#: the radial coefficients of plumb_bob and of the rational model's numerator
RADIAL = ("k1", "k2", "k3")
#: the share of the corners' cost at 1 px per coordinate the prior weighs when every
#: distortion coefficient of the model is :data:`NOMINAL_COEFFICIENT` (mrcal 2.5's rule)
PRIOR_SHARE = 0.0025
#: a coefficient's nominal size for :data:`PRIOR_SHARE`
NOMINAL_COEFFICIENT = 2.0
#: the denominator is held this many times harder than the numerator (mrcal's factor)
DENOMINATOR_FACTOR = 5.0


#: the prior the stated uncertainty assumes at most, per unit of a radial coefficient and of a
#: denominator coefficient: a width of 0.1-0.17 for corners measured to 0.03-0.05 px, the size
#: of real lenses' k2 and k3 (the solve's own weight, grown with the corners, is a pull towards
#: the low orders, not knowledge of the lens)
STATED_RADIAL_PX = 0.3
STATED_DENOMINATOR_PX = 1.0


def coefficient_px(distortion_model: str, corners: int) -> float:
    """The prior's residual (px) per unit of a radial coefficient of a camera whose solve has
    ``corners`` corners (two coordinates each): the prior weighs :data:`PRIOR_SHARE` of the
    corners' cost at 1 px when every coefficient of the model is :data:`NOMINAL_COEFFICIENT`."""
    count = len(LENS_MODELS[distortion_model].coefficients)
    return math.sqrt(PRIOR_SHARE * 2 * corners / (count * NOMINAL_COEFFICIENT ** 2))


def weights(models: list[str], names: list[list[str]],
            columns: list[npt.NDArray[np.int64]], count: int,
            corners: Sequence[int]) -> F64:
    """``(count,)`` the prior's pixels per unit of each unknown (0: no prior), from each
    camera's distortion model, the names of its free intrinsics, their columns and the
    corners its views show."""
    return _weights(models, names, columns, count, corners, stated=False)


def stated_weights(models: list[str], names: list[list[str]],
                   columns: list[npt.NDArray[np.int64]], count: int,
                   corners: Sequence[int]) -> F64:
    """``(count,)`` as :func:`weights`, each at most what the stated uncertainty assumes
    (:data:`STATED_RADIAL_PX`, :data:`STATED_DENOMINATOR_PX`)."""
    return _weights(models, names, columns, count, corners, stated=True)


def _weights(models: list[str], names: list[list[str]],
             columns: list[npt.NDArray[np.int64]], count: int, corners: Sequence[int], *,
             stated: bool) -> F64:
    out = np.zeros(count)
    for model, labels, where, seen in zip(models, names, columns, corners, strict=True):
        if LENS_MODELS[model].fisheye:  # the prior holds pinhole lenses' coefficients
            continue
        radial_px = coefficient_px(model, seen)
        denominator_px = DENOMINATOR_FACTOR * radial_px
        if stated:
            radial_px = min(radial_px, STATED_RADIAL_PX)
            denominator_px = min(denominator_px, STATED_DENOMINATOR_PX)
        for label, column in zip(labels, where, strict=True):
            if label in RADIAL:
                out[column] = radial_px
            elif model == "rational_polynomial" and label in RATIONAL_DENOMINATOR:
                out[column] = denominator_px
    return out
