"""Image buffers of every encoding camlog reads, made from one known RGB scene with OpenCV
(and numpy for the layouts OpenCV has no writer for: bayer mosaics, semi-planar YUV, depth).

The scene is a pure red square on grey; its red pixels' centroid is ``RED_CENTROID`` in
every colour encoding, so a swapped channel order or a wrong bayer pattern loses the red.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

HEIGHT, WIDTH = 48, 64
ROWS, COLS = slice(16, 28), slice(24, 40)  # even bounds: YUV 4:2:2 pairs stay whole
RED_CENTROID = ((COLS.start + COLS.stop - 1) / 2, (ROWS.start + ROWS.stop - 1) / 2)


def scene_rgb() -> np.ndarray:
    """``(H, W, 3)`` uint8: grey 90 with a pure red square."""
    rgb = np.full((HEIGHT, WIDTH, 3), 90, np.uint8)
    rgb[ROWS, COLS] = (255, 0, 0)
    return rgb


def scene_depth_m() -> np.ndarray:
    """``(H, W)`` float32 metres: a ramp 0.5-2.0 m with a 1.25 m square and no
    measurement (0) in the top-left corner."""
    depth = np.tile(np.linspace(0.5, 2.0, WIDTH, dtype=np.float32), (HEIGHT, 1))
    depth[ROWS, COLS] = 1.25
    depth[:4, :4] = 0.0
    return depth


def mosaic(rgb: np.ndarray, pattern: str) -> np.ndarray:
    """The bayer mosaic of an RGB image: ``pattern`` names the colours of each 2x2 block
    in reading order (``rggb``: R at (0, 0), G at (0, 1) and (1, 0), B at (1, 1))."""
    channel = {"r": 0, "g": 1, "b": 2}
    out = np.empty(rgb.shape[:2], rgb.dtype)
    for index, colour in enumerate(pattern):
        dy, dx = divmod(index, 2)
        out[dy::2, dx::2] = rgb[dy::2, dx::2, channel[colour]]
    return out


def nv21(rgb: np.ndarray) -> np.ndarray:
    """V4L2's NV21 of an RGB image from OpenCV's RGB -> YUV 4:2:0 (I420: planes Y, U, V):
    the Y plane, then one plane of V, U pairs for each 2x2 block."""
    height, width = rgb.shape[:2]
    i420 = cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV_I420)
    quarter = height // 4
    u = i420[height:height + quarter].reshape(height // 2, width // 2)
    v = i420[height + quarter:].reshape(height // 2, width // 2)
    return np.vstack([i420[:height], np.dstack([v, u]).reshape(height // 2, width)])


def nv24(rgb: np.ndarray) -> np.ndarray:
    """V4L2's NV24 of an RGB image: the Y plane, then a plane of U, V pairs, one per pixel.
    OpenCV has no 4:4:4 writer; its RGB -> UYVY of the image with every pixel doubled
    gives each pixel's own U and V (a pair of equal pixels shares exact chroma)."""
    height, width = rgb.shape[:2]
    uyvy = cv2.cvtColor(np.repeat(rgb, 2, axis=1), cv2.COLOR_RGB2YUV_UYVY)
    y, u, v = uyvy[:, 0::2, 1], uyvy[:, 0::2, 0], uyvy[:, 1::2, 0]
    return np.vstack([y, np.dstack([u, v]).reshape(2 * height, width)])


@dataclass(frozen=True)
class Case:
    """One encoding: its buffer, what ``rgb8()`` must give and how closely (levels; the
    bayer and 4:2:2 cases are exact away from the square's edges only)."""

    encoding: str
    pixels: np.ndarray
    colour: bool = True  # the red square survives (the red-pixel test applies)
    tolerance: int = 0
    margin: int = 0  # pixels next to an edge of the square left out of the comparison
    depth_m: np.ndarray | None = None  # expected metres for depth encodings


def colour_cases() -> list[Case]:
    """Every colour and grey encoding with its buffer."""
    rgb = scene_rgb()
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    deep = rgb.astype(np.uint16) * 257
    cases = [
        Case("rgb8", rgb), Case("bgr8", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)),
        Case("rgba8", cv2.cvtColor(rgb, cv2.COLOR_RGB2RGBA)),
        Case("bgra8", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGRA)),
        Case("rgb16", deep), Case("bgr16", cv2.cvtColor(deep, cv2.COLOR_RGB2BGR)),
        Case("rgba16", cv2.cvtColor(deep, cv2.COLOR_RGB2RGBA)),
        Case("bgra16", cv2.cvtColor(deep, cv2.COLOR_RGB2BGRA)),
        # cv_bridge reads 3- and 4-channel 8UC as BGR(A)
        Case("8UC3", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)),
        Case("8UC4", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGRA)),
        Case("mono8", grey, colour=False), Case("8UC1", grey, colour=False),
        Case("mono16", grey.astype(np.uint16) * 257, colour=False),
        Case("8UC2", np.dstack([grey, np.zeros_like(grey)]), colour=False),
        Case("yuv422", cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV_UYVY), tolerance=3),
        Case("yuv422_yuy2", cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV_YUY2), tolerance=3),
        Case("nv21", nv21(rgb), tolerance=3),
        Case("nv24", nv24(rgb), tolerance=3),
    ]
    for pattern in ("rggb", "bggr", "gbrg", "grbg"):
        cases.append(Case(f"bayer_{pattern}8", mosaic(rgb, pattern), margin=2))
        cases.append(Case(f"bayer_{pattern}16", mosaic(deep, pattern), margin=2))
    return cases


def depth_cases() -> list[Case]:
    """16UC1 (millimetres) and 32FC1 (metres) depth."""
    depth = scene_depth_m()
    millimetres = np.round(depth * 1000).astype(np.uint16)
    return [Case("16UC1", millimetres, colour=False, depth_m=millimetres / 1000.0),
            Case("32FC1", depth, colour=False, depth_m=depth.astype(np.float64))]


def expected_rgb8(case: Case) -> np.ndarray:
    """What ``Frame.rgb8()`` of a colour or grey case must be."""
    rgb = scene_rgb()
    if case.colour:
        return rgb
    grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
    return cv2.cvtColor(grey, cv2.COLOR_GRAY2RGB)


def compared(case: Case) -> np.ndarray:
    """``(H, W)`` bool: the pixels a case's decoded image is compared on."""
    keep = np.ones((HEIGHT, WIDTH), bool)
    if case.margin:
        edge = np.zeros((HEIGHT, WIDTH), bool)
        m = case.margin
        edge[ROWS.start - m:ROWS.stop + m, COLS.start - m:COLS.stop + m] = True
        edge[ROWS.start + m:ROWS.stop - m, COLS.start + m:COLS.stop - m] = False
        keep &= ~edge
        keep[:m], keep[-m:], keep[:, :m], keep[:, -m:] = False, False, False, False
    return keep
