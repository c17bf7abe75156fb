"""Calibration targets as exact geometry: checkerboard, ChArUco and circle grids.

Every dark feature is a black solid whose face lies on the board plane z = 0, in front of
a white plate, so features sit exactly where the truth says (no texture filtering). The
printed face looks along -z of the board frame (z into the board). The solids are thin
(:data:`BLACK_THICKNESS_M`) and the plate stands :data:`PLATE_GAP_M` behind them: a ray
passing beside a feature's edge at an angle would otherwise meet the feature's side wall and
see it dark, which moves every edge against the ray's sideways travel by the wall's height
times the tangent of the angle (20 um walls moved corners by up to 0.02 px, inwards,
growing towards the image border). With no lights casting shadows the plate looks the same
at any distance behind.

- ``checkerboard``: origin at the first inner corner, x along the ``cols`` inner corners,
  y along the ``rows``.
- ``charuco``: OpenCV's ``CharucoBoard`` (``squares`` cols x rows, ``square_m``, ``marker_m``,
  an OpenCV predefined ArUco dictionary), in OpenCV's board frame: origin at the outer
  corner of the first square, x along the columns, y along the rows. The first square is
  black; each white square holds a marker whose bits are black boxes (runs of cells merged).
- ``textured``: a box whose faces carry a random grey texture (:func:`texture_image`), for
  natural features; the texture is drawn from the target's name, the same in every
  recording.
- ``circles`` / ``acircles``: black disks (``diameter_m``) in OpenCV's symmetric or
  asymmetric grid of ``circles`` cols x rows (``findCirclesGrid``'s pattern size) with
  ``spacing_m``: circle (row i, col j) at ``(j s, i s)``, or ``((2 j + i % 2) s, i s)`` when
  asymmetric; origin at the first circle's centre. Disks are MuJoCo cylinders drawn with
  ``CIRCLE_SLICES`` sides (a regular polygon: its centroid is the circle's centre).
"""

from __future__ import annotations

import math
import zlib

import cv2
import numpy as np

from replay.messages import F64
from replay.records import ScenarioTarget

from .errors import ScenarioError
from .target_spec import TargetSpec

#: thickness of the dark features: their side walls shift an edge seen at angle a by
#: BLACK_THICKNESS_M * tan(a) / 2 on average (0.5 um: under a thousandth of a pixel here)
BLACK_THICKNESS_M = 5e-7
#: space between the features' face and the white plate: far more than a depth-buffer step
#: (about 1.3 um at 0.33 m with znear 5 mm), so the plate never shows through a feature
PLATE_GAP_M = 1e-3
PLATE_THICKNESS_M = 3e-3
#: sides of the polygon MuJoCo draws a disk with (quality numslices)
CIRCLE_SLICES = 120
PLANAR_KINDS = ("checkerboard", "charuco", "circles", "acircles")
#: texels per grain of a textured target's texture
TEXELS_PER_GRAIN = 8


def _vec(values: F64 | list[float] | tuple[float, ...]) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def aruco_dictionary(name: str) -> cv2.aruco.Dictionary:
    """An OpenCV predefined ArUco dictionary by name (``DICT_5X5_100``, ...)."""
    value = getattr(cv2.aruco, name, None) if name.startswith("DICT_") else None
    if not isinstance(value, int):
        names = sorted(n for n in dir(cv2.aruco) if n.startswith("DICT_"))
        raise ScenarioError(f"unknown ArUco dictionary {name!r} (OpenCV's: {', '.join(names)})")
    return cv2.aruco.getPredefinedDictionary(value)


def charuco_board(target: TargetSpec) -> cv2.aruco.CharucoBoard:
    """The OpenCV board a ``charuco`` target is built from (OpenCV's current layout)."""
    board = cv2.aruco.CharucoBoard(target.squares, target.square_m, target.marker_m,
                                   aruco_dictionary(target.dictionary))
    board.setLegacyPattern(False)
    return board


def feature_points_in_target(target: TargetSpec) -> F64:
    """The points a detector finds ``(N, 3)`` in the board frame, in detector order:
    checkerboard inner corners and ChArUco chessboard corners (ids 0..N-1) row-major,
    circle centres row by row."""
    if target.kind == "checkerboard":
        cols, rows = target.inner_corners
        xs, ys = np.meshgrid(np.arange(cols), np.arange(rows))
        grid = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
        return np.asarray(grid * target.square_m, dtype=np.float64)
    if target.kind == "charuco":
        return np.asarray(charuco_board(target).getChessboardCorners(), dtype=np.float64)
    if target.kind in ("circles", "acircles"):
        cols, rows = target.circles
        i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        x = (2 * j + i % 2) if target.kind == "acircles" else j
        grid = np.column_stack([x.ravel(), i.ravel(), np.zeros(i.size)])
        return np.asarray(grid * target.spacing_m, dtype=np.float64)
    raise ValueError(f"{target.kind} target has no feature points")


def markers_in_target(target: TargetSpec) -> tuple[np.ndarray, F64]:
    """A ChArUco target's marker ids ``(M,)`` and their corners ``(M, 4, 3)`` in the board
    frame (OpenCV order: top-left, top-right, bottom-right, bottom-left)."""
    board = charuco_board(target)
    ids = np.asarray(board.getIds(), dtype=np.int64).reshape(-1)
    return ids, np.asarray(board.getObjPoints(), dtype=np.float64).reshape(-1, 4, 3)


def _printed_area(target: TargetSpec) -> tuple[float, float, float, float]:
    """x0, x1, y0, y1 of the features' area (without the plate's border)."""
    if target.kind == "checkerboard":
        cols, rows = target.inner_corners
        s = target.square_m
        return -s, cols * s, -s, rows * s
    if target.kind == "charuco":
        cols, rows = target.squares
        return 0.0, cols * target.square_m, 0.0, rows * target.square_m
    points = feature_points_in_target(target)
    r = target.diameter_m / 2
    return (float(points[:, 0].min() - r), float(points[:, 0].max() + r),
            float(points[:, 1].min() - r), float(points[:, 1].max() + r))


def outline_in_target(target: TargetSpec) -> F64:
    """Points ``(N, 3)`` that must be visible for the target to count as fully in view."""
    if target.kind in PLANAR_KINDS:
        x0, x1, y0, y1 = _printed_area(target)
        return np.array([[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]])
    half = target.size_m / 2
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return np.asarray(signs * half, dtype=np.float64)


def center_in_target(target: TargetSpec) -> F64:
    """The middle of the target's features (3,), where random poses aim."""
    if target.kind == "checkerboard":
        cols, rows = target.inner_corners
        return np.array([(cols - 1) / 2, (rows - 1) / 2, 0.0]) * target.square_m
    if target.kind in PLANAR_KINDS:
        x0, x1, y0, y1 = _printed_area(target)
        return np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    return np.zeros(3)


def _black_box(x0: float, x1: float, y0: float, y1: float) -> str:
    center = ((x0 + x1) / 2, (y0 + y1) / 2, BLACK_THICKNESS_M / 2)
    half = ((x1 - x0) / 2, (y1 - y0) / 2, BLACK_THICKNESS_M / 2)
    return f'<geom type="box" pos="{_vec(center)}" size="{_vec(half)}" material="black"/>'


def _plate(target: TargetSpec) -> str:
    x0, x1, y0, y1 = _printed_area(target)
    b = target.border_m
    center = ((x0 + x1) / 2, (y0 + y1) / 2, PLATE_GAP_M + PLATE_THICKNESS_M / 2)
    half = ((x1 - x0) / 2 + b, (y1 - y0) / 2 + b, PLATE_THICKNESS_M / 2)
    return f'<geom type="box" pos="{_vec(center)}" size="{_vec(half)}" material="white"/>'


def cell_rectangles(black: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Cover the True cells of a 2-D grid with rectangles (row0, col0, row1, col1),
    ends exclusive: runs along each row, grown down while the rows below are black there."""
    used = np.zeros_like(black, dtype=bool)
    out = []
    rows, cols = black.shape
    for r in range(rows):
        c = 0
        while c < cols:
            if not black[r, c] or used[r, c]:
                c += 1
                continue
            end = c
            while end < cols and black[r, end] and not used[r, end]:
                end += 1
            bottom = r + 1
            while (bottom < rows and black[bottom, c:end].all()
                   and not used[bottom, c:end].any()):
                bottom += 1
            used[r:bottom, c:end] = True
            out.append((r, c, bottom, end))
            c = end
    return out


def black_rectangles(target: TargetSpec) -> list[tuple[float, float, float, float]]:
    """The black areas (x0, x1, y0, y1) of a checkerboard or ChArUco target in its board
    frame: squares and, for ChArUco, runs of marker cells."""
    s = target.square_m
    if target.kind == "checkerboard":
        cols, rows = target.inner_corners
        return [((j - 1) * s, j * s, (i - 1) * s, i * s)
                for i in range(rows + 1) for j in range(cols + 1) if (i + j) % 2 == 0]
    board = charuco_board(target)
    cols, rows = target.squares
    ids, corners = markers_in_target(target)
    marker_squares = {(int(c[:, 1].mean() // s), int(c[:, 0].mean() // s)) for c in corners}
    out = [(j * s, (j + 1) * s, i * s, (i + 1) * s)
           for i in range(rows) for j in range(cols) if (i, j) not in marker_squares]
    dictionary = board.getDictionary()
    cells = dictionary.markerSize + 2  # bits plus the black border
    for marker_id, corner in zip(ids, corners, strict=True):
        bits = cv2.aruco.generateImageMarker(dictionary, int(marker_id), cells) == 0
        x0, y0 = corner[0, 0], corner[0, 1]
        cell = (corner[1, 0] - x0) / cells
        out += [(x0 + c0 * cell, x0 + c1 * cell, y0 + r0 * cell, y0 + r1 * cell)
                for r0, c0, r1, c1 in cell_rectangles(bits)]
    return out


def _circle_geoms(target: TargetSpec) -> list[str]:
    r = target.diameter_m / 2
    return [f'<geom type="cylinder" pos="{_vec((x, y, BLACK_THICKNESS_M / 2))}" '
            f'size="{_vec((r, BLACK_THICKNESS_M / 2))}" material="black"/>'
            for x, y, _ in feature_points_in_target(target)]


def target_geoms(target: TargetSpec) -> list[str]:
    """MJCF geoms of a planar target in its board frame: the plate and its black features."""
    if target.kind in ("circles", "acircles"):
        return [_plate(target), *_circle_geoms(target)]
    return [_plate(target), *(_black_box(*r) for r in black_rectangles(target))]


def texture_image(target: TargetSpec) -> np.ndarray:
    """A ``textured`` target's texture ``(N, N)`` uint8, drawn on each face of its box: grey
    blobs about ``grain_m`` across its largest face with sharp edges (smoothed noise pushed
    towards black and white), and half as large ones within them, so that corners stand
    out at two scales."""
    grains = max(4, math.ceil(float(np.max(target.size_m)) / target.grain_m))
    side = grains * TEXELS_PER_GRAIN
    rng = np.random.default_rng(zlib.crc32(target.name.encode()))
    texture = np.zeros((side, side))
    for scale, weight in ((grains, 1.0), (2 * grains, 0.5)):
        noise = rng.standard_normal((scale, scale))
        texture += weight * cv2.resize(noise, (side, side), interpolation=cv2.INTER_CUBIC)
    texture /= float(np.std(texture))
    return np.asarray(np.clip(127.5 + 120.0 * np.tanh(1.5 * texture), 0, 255), dtype=np.uint8)


def check_target(target: TargetSpec) -> None:
    """Raise ScenarioError for a target that cannot be built as specified."""
    if target.kind == "charuco":
        dictionary = aruco_dictionary(target.dictionary)
        if target.marker_m >= target.square_m:
            raise ScenarioError(f"marker_m must be smaller than square_m "
                                f"({target.marker_m} >= {target.square_m})")
        cols, rows = target.squares
        if cols * rows // 2 > len(dictionary.bytesList):
            raise ScenarioError(f"{target.dictionary} has {len(dictionary.bytesList)} markers, "
                                f"too few for {cols}x{rows} squares")
    if target.kind in ("circles", "acircles"):
        gap = target.spacing_m * (math.sqrt(2) if target.kind == "acircles" else 1.0)
        if target.diameter_m >= gap:
            raise ScenarioError(f"circles {target.diameter_m} m across overlap at a spacing of "
                                f"{target.spacing_m} m")


def target_record(target: TargetSpec) -> ScenarioTarget:
    """The geometry of a target as the scenario record holds it."""
    if target.kind == "checkerboard":
        return ScenarioTarget(
            name=target.name, kind=target.kind, inner_corners=target.inner_corners,
            square_m=target.square_m, corners_in_target=feature_points_in_target(target),
            frame="origin at the first inner corner, x along cols, y along rows, "
                  "z into the board")
    if target.kind == "charuco":
        ids, corners = markers_in_target(target)
        points = feature_points_in_target(target)
        return ScenarioTarget(
            name=target.name, kind=target.kind, squares=target.squares,
            square_m=target.square_m, marker_m=target.marker_m, dictionary=target.dictionary,
            legacy_pattern=False, corners_in_target=points,
            corner_ids=list(range(len(points))), marker_ids=ids.tolist(),
            marker_corners_in_target=corners,
            frame="OpenCV's CharucoBoard frame: origin at the outer corner of the first "
                  "(black) square, x along cols, y along rows, z into the board")
    if target.kind in ("circles", "acircles"):
        return ScenarioTarget(
            name=target.name, kind=target.kind, circles=target.circles,
            spacing_m=target.spacing_m, diameter_m=target.diameter_m,
            asymmetric=target.kind == "acircles",
            centres_in_target=feature_points_in_target(target),
            frame="origin at the first circle's centre, x along cols, y along rows, "
                  "z into the board")
    if target.kind == "textured":
        return ScenarioTarget(name=target.name, kind=target.kind, size_m=target.size_m,
                              grain_m=target.grain_m, frame="origin at the box centre")
    return ScenarioTarget(name=target.name, kind=target.kind, size_m=target.size_m,
                          rgba=tuple(target.rgba), frame="origin at the box centre")
