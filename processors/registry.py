"""The processors camlog knows. A new processor is one module, its test and one entry here.

Each entry declares the processor's options, outputs and how each output is displayed; the
``camlog process`` flags, the batch pipelines' ``process`` step and the record that
``camlog view`` reads are generated from these entries. Importing this module loads
neither OpenCV nor numpy: the implementation is imported when a processor is built.
"""

from __future__ import annotations

from typing import Any

from replay.display import Display
from replay.msgtypes import IMAGE, POINT_STAMPED

from .errors import ConfigError
from .spec import Configured, Option, OptionKind, OutputSpec, ProcessorSpec

__all__ = ["PROCESSORS", "SPECS", "configure", "make_processor", "spec_of"]

_INT, _FLOAT, _TEXT = OptionKind.INT, OptionKind.FLOAT, OptionKind.TEXT

#: a camera's calibration file, given with the processor's flag (``--rectify OST.YAML``)
CALIBRATION = Option("camera_info", OptionKind.CAMERA_INFO, None, "calibration file",
                     metavar="OST.YAML", required=True)

SPECS: tuple[ProcessorSpec, ...] = (
    ProcessorSpec(
        name="red_pixels",
        summary="mask of pixels with R > RATIO*(G+B) and a blue square at their centroid",
        implementation="processors.red_pixels:RedPixels",
        options=(Option("ratio", _INT, 10, "redness ratio", minimum=0),),
        outputs=(
            OutputSpec("output_video", IMAGE, Display.MASK, "red pixels",
                       "rgb8 mask, blue square at the centroid", entity="red_pixels/mask"),
            OutputSpec("red_centroid", POINT_STAMPED, Display.POINT_2D, "red centroid",
                       "x = u, y = v px; none when nothing is red",
                       entity="red_pixels/centroid"),
            OutputSpec("red_count", POINT_STAMPED, Display.SCALAR, "red pixel count", "x = count",
                       entity="red_pixel_count"),
        ),
        title="red pixels (the chapter's find_red_pixels)",
    ),
    ProcessorSpec(
        name="edges",
        summary="grayscale + Canny edges",
        implementation="processors.edges:Edges",
        options=(Option("low", _FLOAT, 50.0, "Canny low threshold", minimum=0),
                 Option("high", _FLOAT, 150.0, "Canny high threshold", minimum=0)),
        outputs=(OutputSpec("edges", IMAGE, Display.EDGES, "Canny edges", "mono8, 255 on "
                            "edges", entity="edges"),),
        title="edges (the chapter's find_features)",
    ),
    ProcessorSpec(
        name="rectify",
        summary="undistort and rectify with a camera_info_manager calibration (K, D, R, P)",
        implementation="processors.rectify:Rectifier",
        options=(CALIBRATION,),
        outputs=(OutputSpec("image_rect", IMAGE, Display.RECTIFIED, "rectified image",
                            "input encoding and size"),),
        primary="camera_info", title="rectify (image_proc)",
    ),
    ProcessorSpec(
        name="undistort",
        summary="remove lens distortion, keeping the camera matrix K (cv2.undistort's image; "
                "for a stereo pair's rectification use rectify)",
        implementation="processors.undistort:Undistort",
        options=(CALIBRATION,),
        outputs=(OutputSpec("image_undistorted", IMAGE, Display.IMAGE, "undistorted image",
                            "input encoding and size, camera matrix K"),),
        primary="camera_info", title="undistort",
    ),
    ProcessorSpec(
        name="resize",
        summary="resize to WxH pixels or by a scale (area average when shrinking)",
        implementation="processors.resize:Resize",
        options=(Option("size", _TEXT, None, "WxH or a scale", metavar="WxH|SCALE",
                        required=True, example="24x18"),),
        outputs=(OutputSpec("image_resized", IMAGE, Display.IMAGE, "resized image",
                            "input encoding"),),
        primary="size", title="resize (image_proc)",
    ),
    ProcessorSpec(
        name="throttle",
        summary="keep every N-th frame, or at most HZ frames per second of header stamp "
                "(topic_tools throttle); kept frames pass through unchanged",
        implementation="processors.throttle:make_throttle",
        options=(
            Option("every", _INT, None, "every N-th frame", metavar="N", minimum=1),
            Option("rate", _FLOAT, None, "at most HZ frames per second of header stamp",
                   metavar="HZ", above=0),
        ),
        flag=False, selects=True, exclusive=("every", "rate"), title="throttle",
    ),
)

#: name -> declaration
PROCESSORS: dict[str, ProcessorSpec] = {spec.name: spec for spec in SPECS}


def spec_of(name: str) -> ProcessorSpec:
    """The declaration of the processor called ``name``."""
    if name not in PROCESSORS:
        raise ConfigError(f"unknown processor {name!r} (known: {', '.join(PROCESSORS)})")
    return PROCESSORS[name]


def configure(name: str, **options: Any) -> Configured:
    """A registered processor with checked options (not built yet)."""
    return spec_of(name).configure(options)


def make_processor(name: str, **options: Any) -> Any:
    """Build a registered processor with its options."""
    return configure(name, **options).build()
