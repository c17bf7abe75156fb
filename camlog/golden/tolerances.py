"""How far each golden number or image may move, and why: :data:`TOLERANCES`."""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass

__all__ = ["TOLERANCES", "Tolerance", "tolerance_for"]


@dataclass(frozen=True)
class Tolerance:
    """``|actual - expected| <= abs + rel * |expected|`` for numbers; ``RMS <= abs`` for images.

    ``pattern`` is matched (fnmatch) against ``ARTIFACT:KEY`` for numbers, where KEY is the
    number's path in its JSON/YAML tree (``cameras[0].parameters.fx.value``), and against
    ``ARTIFACT`` for images.
    """

    pattern: str
    abs: float
    rel: float
    unit: str
    why: str

    def allows(self, expected: float, actual: float) -> bool:
        """Whether ``actual`` is within the tolerance of ``expected``."""
        return abs(actual - expected) <= self.abs + self.rel * abs(expected)

    def describe(self) -> str:
        """The tolerance in words."""
        parts = [f"abs {self.abs:g}{' ' + self.unit if self.unit else ''}"] if self.abs else []
        parts += [f"rel {self.rel:g}"] if self.rel else []
        return " + ".join(parts) or "exact"


# Calibration rows: when every detected corner moves by +-1e-4 px (a few float32 ulps at
# 640 px, how far cornerSubPix may land on another CPU or OpenCV build), the largest change
# seen over four trials is given as "moves"; each tolerance is about 5x that and far below
# the parameter's standard deviation. A changed detection or view selection is caught
# exactly by the view counts and the rejected list.
#: first match wins; everything not listed must be equal
TOLERANCES: tuple[Tolerance, ...] = (
    # --- images: RMS over all pixels and channels
    Tolerance("*/image_rect-*.png", 2.0, 0.0, "levels",
              "bilinear remap through a calibration that may itself move within its "
              "tolerance (K by 0.03 px)"),
    Tolerance("*.png", 0.5, 0.0, "levels",
              "Canny, the red mask and its marker are integer arithmetic (bit-exact); 0.5 "
              "allows one flipped pixel of 640x480 (RMS 0.46)"),
    # --- processors
    Tolerance("*/red_centroid.json:*_px", 1e-6, 0.0, "px",
              "mean of integer coordinates, exact up to double rounding; one more mask pixel "
              "moves it by >= 1e-5 px"),
    Tolerance("*/edges.json:*edge_pixels", 1.0, 0.0, "pixels",
              "one flipped pixel per frame, as for the edge images"),
    # --- calibration.json subset (per camera, then stereo)
    Tolerance("*:*parameters.??.std", 0.0, 1e-3, "", "moves 1.4e-4 relative"),
    Tolerance("*:*parameters.f?.value", 0.03, 0.0, "px", "moves 0.0014 px; sigma ~0.5 px"),
    Tolerance("*:*parameters.c?.value", 0.03, 0.0, "px", "moves 0.0054 px; sigma ~1 px"),
    Tolerance("*:*parameters.k1.value", 1e-4, 0.0, "", "moves 1.6e-5; sigma ~4e-3"),
    Tolerance("*:*parameters.p?.value", 1e-4, 0.0, "", "moves 1.9e-6; sigma ~4e-4"),
    Tolerance("*:*parameters.k?.value", 1e-3, 0.0, "", "k2..k6: k2 moves 2.2e-4; sigma ~0.05"),
    Tolerance("*:*rms_px", 1e-4, 0.0, "px", "reprojection / epipolar RMS moves 8e-6 px"),
    Tolerance("*:*cross_validation_px", 0.05, 0.0, "px",
              "worst of half the difference of two half-corner calibrations"),
    Tolerance("*:*vs_truth*_px", 0.05, 0.0, "px", "moves 0.0038 px"),
    Tolerance("*:*translation_m*", 5e-6, 0.0, "m", "moves 7e-7 m (z, along the optical axis)"),
    Tolerance("*:*_m", 5e-7, 0.0, "m", "baseline, its sigma and the square move 8e-8 m"),
    Tolerance("*:*rotation_deg", 2e-3, 0.0, "deg", "moves 2.7e-4 deg"),
    # --- calibration YAML (camera_info_manager)
    Tolerance("*.yaml:camera_matrix.*", 0.03, 0.0, "px", "as fx, fy, cx, cy"),
    Tolerance("*.yaml:projection_matrix.*", 0.2, 0.0, "px",
              "moves 0.04 px: with alpha 0 the new camera is cropped to valid pixels, which "
              "amplifies K and D changes"),
    Tolerance("*.yaml:rectification_matrix.*", 2e-4, 0.0, "", "moves 3.5e-5"),
    Tolerance("*.yaml:distortion_coefficients.*", 1e-3, 0.0, "",
              "the loosest coefficient's (k2); calibration.json checks each one"),
    Tolerance("*", 0.0, 0.0, "",
              "stamps, counts, sizes, pairings and numbers copied from the input are exact"),
)


def tolerance_for(subject: str) -> Tolerance:
    """The first :data:`TOLERANCES` row whose pattern matches ``ARTIFACT[:KEY]``."""
    for tolerance in TOLERANCES:
        if fnmatch.fnmatchcase(subject, tolerance.pattern):
            return tolerance
    raise AssertionError("the last row matches everything")
