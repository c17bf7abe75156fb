"""Targets of a scenario spec and how they move."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from replay.geometry import rotation_from_rpy
from replay.messages import F64

from .cameras import CameraSpec
from .spec_table import SpecTable


@dataclass(frozen=True)
class MotionSpec:
    """How a target moves: ``static``, ``random_hold`` (random poses held ``hold_s``) or
    ``smooth`` (never still: a C1 path through a random pose every ``segment_s``)."""

    kind: str
    hold_s: float
    segment_s: float
    center_m: F64
    xy_range_m: float
    z_range_m: tuple[float, float]
    max_tilt_rad: float
    partial_view_probability: float
    world_from_target: F64  # (4, 4), for static
    #: "world": poses within center_m +- xy_range_m, z_range_m, facing up; "image": poses
    #: facing a camera at distance_m, pushed in turn into each image corner, edge and the middle
    aim: str = "world"
    distance_m: tuple[float, float] = (0.12, 0.22)
    #: "all": fully visible in every camera; "any": in the camera it is aimed at (in turn)
    visible_in: str = "all"
    #: aim = image: no point of the target further than this from the camera's axis
    max_view_angle_rad: float = 1.5


@dataclass(frozen=True)
class TargetSpec:
    """A target and how it moves; its geometry fields are those of its ``kind``
    (:mod:`recorder.targets` builds and documents each):

    - ``checkerboard``: ``inner_corners`` (cols, rows), ``square_m``;
    - ``charuco``: ``squares`` (cols, rows), ``square_m``, ``marker_m``, ``dictionary``;
    - ``circles`` / ``acircles``: ``circles`` (cols, rows), ``spacing_m``, ``diameter_m``;
    - ``box``: ``size_m`` (3,) full extents, ``rgba``;
    - ``textured``: a box of ``size_m`` whose faces carry a random texture of blobs about
      ``grain_m`` across (natural features for a moving rig to see).

    A planar target's white plate reaches ``border_m`` beyond its features.
    """

    name: str
    kind: str
    motion: MotionSpec
    inner_corners: tuple[int, int] = (7, 6)
    square_m: float = 0.01
    border_m: float = 0.01
    squares: tuple[int, int] = (5, 7)
    marker_m: float = 0.0075
    dictionary: str = "DICT_5X5_100"
    circles: tuple[int, int] = (4, 11)
    spacing_m: float = 0.01
    diameter_m: float = 0.005
    size_m: F64 = field(default_factory=lambda: np.array([0.02, 0.02, 0.01]))
    rgba: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 1.0)
    grain_m: float = 0.01


#: a textured box's largest extent holds at most this many grains (its texture's size)
MAX_GRAINS = 400

TARGET_KINDS = ("checkerboard", "charuco", "circles", "acircles", "box", "textured")


def _grid(f: SpecTable, key: str, default: list[int], low: int) -> tuple[int, int]:
    value = f.vector(key, 2, default)
    if np.any(value < low) or np.any(value != np.round(value)):
        raise f.fail(key, f"expected two integers >= {low}, got {value.tolist()}")
    return int(value[0]), int(value[1])


def _geometry(f: SpecTable, kind: str) -> dict[str, Any]:
    """The geometry fields of one target kind, read from its table."""
    if kind == "checkerboard":
        square_m = f.number("square_m", 0.01, positive=True)
        return {"inner_corners": _grid(f, "inner_corners", [7, 6], 2), "square_m": square_m,
                "border_m": f.number("border_squares", 1.0, low=0.25) * square_m}
    if kind == "charuco":
        square_m = f.number("square_m", 0.01, positive=True)
        return {"squares": _grid(f, "squares", [5, 7], 3), "square_m": square_m,
                "marker_m": f.number("marker_m", 0.75 * square_m, positive=True),
                "dictionary": f.text("dictionary", "DICT_5X5_100"),
                "border_m": f.number("border_squares", 0.5, low=0.25) * square_m}
    if kind in ("circles", "acircles"):
        spacing_m = f.number("spacing_m", 0.01, positive=True)
        return {"circles": _grid(f, "circles", [4, 11] if kind == "acircles" else [7, 6], 2),
                "spacing_m": spacing_m,
                "diameter_m": f.number("diameter_m", 0.5 * spacing_m, positive=True),
                "border_m": f.number("border_spacings", 1.0, low=0.25) * spacing_m}
    size_m = f.vector("size_m", 3, [0.02, 0.02, 0.01])
    if np.any(size_m <= 0):
        raise f.fail("size_m", "extents must be > 0")
    if kind == "textured":
        grain_m = f.number("grain_m", 0.01, positive=True)
        if float(size_m.max()) / grain_m > MAX_GRAINS:
            raise f.fail("grain_m", f"more than {MAX_GRAINS} grains across the box; make "
                                    "them larger")
        return {"size_m": size_m, "grain_m": grain_m}
    color = f.vector("rgba", 4, [1.0, 0.0, 0.0, 1.0])
    return {"size_m": size_m,
            "rgba": (float(color[0]), float(color[1]), float(color[2]), float(color[3]))}


def parse_target(
    table: Any, where: str, source: str, cameras: list[CameraSpec]
) -> TargetSpec:
    """Resolve one ``[[targets]]`` table (``cameras`` for poses relative to a camera)."""
    f = SpecTable(table, where, source)
    name = f.text("name")
    kind = f.text("kind", choices=TARGET_KINDS)
    geometry = _geometry(f, kind)
    motion = parse_motion(f.get("motion", {"kind": "static"}), f"{where}motion.", source, cameras)
    f.check_unknown()
    return TargetSpec(name, kind, motion, **geometry)


def parse_motion(table: Any, where: str, source: str, cameras: list[CameraSpec]) -> MotionSpec:
    """Resolve a target's ``motion`` table."""
    f = SpecTable(table, where, source)
    kind = f.text("kind", choices=("static", "random_hold", "smooth"))
    world_from_target = np.eye(4)
    if kind == "static":
        target_pose = np.eye(4)
        target_pose[:3, :3] = rotation_from_rpy(f.vector("rotation_rpy_rad", 3, [0, 0, 0]))
        target_pose[:3, 3] = f.vector("position_m", 3, [0, 0, 0])
        frame = f.text("relative_to", "world")
        if frame == "world":
            world_from_target = target_pose
        else:
            parents = [c for c in cameras if c.name == frame]
            if not parents:
                raise f.fail("relative_to", f"no camera named {frame!r} (or use 'world')")
            world_from_target = parents[0].world_from_camera @ target_pose
    z_range = f.vector("z_range_m", 2, [0.15, 0.27])
    distance = f.vector("distance_m", 2, [0.12, 0.22])
    for key, bounds in (("z_range_m", z_range), ("distance_m", distance)):
        if bounds[0] > bounds[1]:
            raise f.fail(key, "lower bound above upper bound")
    spec = MotionSpec(
        kind=kind,
        hold_s=f.number("hold_s", 0.5, positive=True),
        segment_s=f.number("segment_s", 0.6, positive=True),
        center_m=f.vector("center_m", 3, [0.0, 0.0, 0.2]),
        xy_range_m=f.number("xy_range_m", 0.05, low=0.0),
        z_range_m=(float(z_range[0]), float(z_range[1])),
        max_tilt_rad=f.number("max_tilt_rad", 0.6, low=0.0, high=1.4),
        partial_view_probability=f.number("partial_view_probability", 0.0, low=0.0, high=1.0),
        world_from_target=world_from_target,
        aim=f.text("aim", "world", choices=("world", "image")),
        distance_m=(float(distance[0]), float(distance[1])),
        visible_in=f.text("visible_in", "all", choices=("all", "any")),
        max_view_angle_rad=f.number("max_view_angle_rad", 1.5, low=0.1, high=3.0),
    )
    f.check_unknown()
    if spec.aim == "image" and kind != "random_hold":
        raise f.fail("aim", f"aim = 'image' plans held poses (kind = 'random_hold'), not {kind!r}")
    return spec
