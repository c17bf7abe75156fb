"""What a calibration estimates: lens model, coefficients, fixed parameters, tangential test.

Options keep camera_calibration's meaning: ``fix_principal_point`` holds (cx, cy) at the
image centre, ``fix_aspect_ratio`` forces fx = fy, and ``k_coefficients`` radial terms are
estimated. The lens ``model`` is a ROS ``distortion_model``: ``plumb_bob`` (k1 k2 p1 p2 k3),
``rational_polynomial`` (k1..k6 with p1 p2) or ``equidistant`` (fisheye k1..k4, no tangential
terms); ``fisheye`` is accepted for equidistant. Without a model, ``k_coefficients`` > 3
selects rational_polynomial, as camera_calibration's ``-k`` does. With ``choose_order``
the radial order (plumb_bob k1 k2 or k1 k2 k3, rational_polynomial k1..k6 unless plumb_bob
is named) is chosen per camera by cross-validation over the views (:mod:`.model_order`).

Tangential distortion (p1, p2) is held at zero (``"zero"``), always estimated
(``"estimate"``) or, by default (``"auto"``), estimated only when the views show it: a
likelihood-ratio test of the two fits. At a narrow field of view p1, p2 trade almost freely
against the principal point and a small turn of the camera, so estimating them when the lens
has none costs principal point accuracy.

The board's warp (:mod:`.warp`) is held flat (``board_warp="off"``), estimated (``"on"``) or
estimated when cross-validation over the views shows it (``"auto"``, :mod:`.warp_choice`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from replay.lens_models import LENS_MODEL_NAMES, LENS_MODELS, canonical_name, lens_model

from ..errors import ProcessorError
from .patterns import WARP_MODES

TANGENTIAL_MODES = ("auto", "estimate", "zero")
#: "auto" keeps p1, p2 when holding them at zero raises the residual more than noise would
#: with this probability (the residual is not quite independent noise: views share small
#: biases, so the test is strict)
TANGENTIAL_P_VALUE = 1e-3


def tangential_mode(zero_tangent_dist: bool, tangent_dist: bool) -> str:
    """The tangential mode of camera_calibration-style flags: --zero-tangent-dist holds
    p1 = p2 = 0, --tangent-dist always estimates them, neither lets the views decide."""
    if zero_tangent_dist and tangent_dist:
        raise ProcessorError("holding tangential distortion at zero and always estimating it "
                             "contradict each other")
    return "zero" if zero_tangent_dist else "estimate" if tangent_dist else "auto"


@dataclass(frozen=True)
class CalibrationOptions:
    """Lens model and what is held fixed (see the module docstring)."""

    fix_principal_point: bool = False
    fix_aspect_ratio: bool = False
    tangential: str = "auto"
    k_coefficients: int | None = None
    model: str | None = None
    choose_order: bool = False
    board_warp: str = "off"

    def __post_init__(self) -> None:
        if self.choose_order and (self.k_coefficients is not None
                                  or self.model not in (None, "plumb_bob")):
            raise ProcessorError("the radial order is chosen among plumb_bob's and "
                                 "rational_polynomial's: give no number of radial "
                                 "coefficients and no lens model other than plumb_bob")
        if self.model is not None:
            model = canonical_name(self.model)
            if model not in LENS_MODELS:
                raise ProcessorError(f"unknown lens model {self.model!r} "
                                     f"(use {', '.join(LENS_MODEL_NAMES)})")
            object.__setattr__(self, "model", model)
        k = self.k_coefficients
        most = lens_model(self.distortion_model).max_radial
        if k is not None and not 0 <= k <= most:
            raise ProcessorError(f"the number of radial coefficients must be 0..{most} for "
                                 f"{self.distortion_model}, got {k}")
        if self.tangential not in TANGENTIAL_MODES:
            raise ProcessorError(f"tangential distortion must be one of "
                                 f"{', '.join(TANGENTIAL_MODES)}, got {self.tangential!r}")
        if self.board_warp not in WARP_MODES:
            raise ProcessorError(f"the board warp must be one of {', '.join(WARP_MODES)}, "
                                 f"got {self.board_warp!r}")

    def with_tangential(self, mode: str) -> CalibrationOptions:
        """The same options with another tangential mode."""
        return dataclasses.replace(self, tangential=mode)

    @property
    def distortion_model(self) -> str:
        """The ROS distortion model the options estimate."""
        if self.model is not None:
            return self.model
        return "rational_polynomial" if (self.k_coefficients or 0) > 3 else "plumb_bob"

    @property
    def radial_count(self) -> int:
        """How many radial coefficients are estimated."""
        if self.k_coefficients is not None:
            return self.k_coefficients
        return lens_model(self.distortion_model).default_radial

    @property
    def has_tangential(self) -> bool:
        """Whether the model has p1, p2 at all."""
        return lens_model(self.distortion_model).tangential

    @property
    def free(self) -> tuple[str, ...]:
        """Names of the estimated intrinsics (fx and fy both, also with a fixed aspect ratio:
        then they move together)."""
        names = ["fx", "fy"]
        if not self.fix_principal_point:
            names += ["cx", "cy"]
        names += [f"k{i}" for i in range(1, self.radial_count + 1)]
        if self.has_tangential and self.tangential != "zero":
            names += ["p1", "p2"]
        order = lens_model(self.distortion_model).intrinsic_names
        return tuple(n for n in order if n in names)

    @property
    def free_intrinsics(self) -> int:
        """How many intrinsic parameters the solver estimates."""
        return len(self.free) - (1 if self.fix_aspect_ratio else 0)


@dataclass(frozen=True)
class TangentialTest:
    """Does the fit need p1, p2? ``chi2`` is the rise in the residual sum of squares when
    they are held at zero, in units of the free fit's residual variance; under "no
    tangential distortion" it follows a chi-square law with 2 degrees of freedom."""

    chi2: float
    estimated: bool  # the outcome: p1, p2 kept

    @property
    def p_value(self) -> float:
        """Probability of a rise this large without tangential distortion."""
        return math.exp(-max(self.chi2, 0.0) / 2.0)

    def describe(self) -> str:
        """The test and its outcome in words."""
        verdict = ("estimated" if self.estimated
                   else "held at zero (the views do not show any)")
        return (f"tangential distortion {verdict}: holding p1 = p2 = 0 raises the residual by "
                f"chi2(2) = {self.chi2:.1f}, p = {self.p_value:.2g} "
                f"(kept when p < {TANGENTIAL_P_VALUE:g})")
