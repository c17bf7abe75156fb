"""The lens models camlog understands: one table, one entry per model.

Each entry is what every part of camlog needs to know about a ROS ``distortion_model`` (the
name calibration YAML files carry): the names of its distortion coefficients in ``D``'s
order, whether it is a fisheye (its field of view may pass 180 degrees, beyond any pinhole
image), how many radial coefficients a calibration estimates by default and at most,
whether it has tangential terms, and the extra OpenCV calibration flag that selects it.

Its functions stand in tables keyed by the same name, beside the code that needs them:
:data:`replay.projections.PROJECTIONS` (projection, unprojection and rectification maps),
``processors.calibration.lens.DISTORTIONS`` (the solver's distortion with derivatives) and
``processors.calibration.opencv_lens.OPENCV_LENSES`` (OpenCV's calibration, stereo
rectification and new camera matrix). A new lens model is one entry here, one in each of
those tables, and ``tests/replay/test_lens_models.py`` holds every entry to them.

>>> lens_model("fisheye").name, lens_model("plumb_bob").coefficients
('equidistant', ('k1', 'k2', 'p1', 'p2', 'k3'))
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LENS_MODELS", "LENS_MODEL_NAMES", "MODEL_ALIASES", "LensModel", "canonical_name",
           "lens_model"]


@dataclass(frozen=True)
class LensModel:
    """One lens model (see the module docstring)."""

    name: str  # the ROS distortion_model
    coefficients: tuple[str, ...]  # names of D, in order
    fisheye: bool  # a fisheye lens: its field of view may pass 180 degrees
    default_radial: int  # radial coefficients a calibration estimates unless told
    max_radial: int
    tangential: bool  # has p1, p2
    opencv_flag: str = ""  # the cv2.CALIB_* flag that selects the model in calibrateCamera

    @property
    def intrinsic_names(self) -> tuple[str, ...]:
        """fx fy cx cy, then the coefficients: the calibration solver's intrinsic vector."""
        return ("fx", "fy", "cx", "cy", *self.coefficients)

    @property
    def radial_names(self) -> tuple[str, ...]:
        """The radial coefficients, k1 first."""
        return tuple(n for n in self.coefficients if n.startswith("k"))


LENS_MODELS: dict[str, LensModel] = {m.name: m for m in (
    LensModel("plumb_bob", ("k1", "k2", "p1", "p2", "k3"), fisheye=False, default_radial=2,
              max_radial=3, tangential=True),
    LensModel("rational_polynomial", ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"),
              fisheye=False, default_radial=6, max_radial=6, tangential=True,
              opencv_flag="CALIB_RATIONAL_MODEL"),
    LensModel("equidistant", ("k1", "k2", "k3", "k4"), fisheye=True, default_radial=4,
              max_radial=4, tangential=False),
)}
#: other names of the models (OpenCV and Kalibr call the equidistant model "fisheye")
MODEL_ALIASES = {"fisheye": "equidistant"}
#: every name a lens model may be given by: the ROS names, then the aliases (``--model``'s
#: choices)
LENS_MODEL_NAMES = (*LENS_MODELS, *MODEL_ALIASES)


def canonical_name(name: str) -> str:
    """The ROS name of a model (``fisheye`` -> ``equidistant``); an empty name is plumb_bob,
    as camera_info_manager reads it."""
    name = (name or "plumb_bob").strip()
    return MODEL_ALIASES.get(name, name)


def lens_model(name: str) -> LensModel:
    """The table's entry for ``name`` (or one of its aliases); KeyError listing the known
    models otherwise."""
    try:
        return LENS_MODELS[canonical_name(name)]
    except KeyError:
        known = ", ".join(LENS_MODEL_NAMES)
        raise KeyError(f"unknown lens model {name!r} (use {known})") from None
