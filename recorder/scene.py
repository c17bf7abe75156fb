"""MJCF for a scenario: ground, light, cameras and mocap-driven targets.

Calibration targets are geometry, not textures, so that their features are exact
(:mod:`recorder.targets`).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from replay.geometry import OPTICAL_FROM_MJCAMERA, quat_xyzw_from_rotation
from replay.messages import F64

from .optics import View
from .scenario import ScenarioSpec
from .targets import CIRCLE_SLICES, PLANAR_KINDS, target_geoms

#: MuJoCo's headlight shines along the rendering camera's view; a camera rendered as several
#: views gets the same light as a fixed directional light along its optical axis instead
#: (``camera_light_name``), so that its views agree where they meet
HEADLIGHT_AMBIENT = (0.45, 0.45, 0.45)
HEADLIGHT_DIFFUSE = (0.5, 0.5, 0.5)


def _vec(values: F64 | list[float] | tuple[float, ...]) -> str:
    return " ".join(f"{float(v):.9g}" for v in values)


def view_camera_name(camera_name: str, index: int) -> str:
    """MJCF name of one of a camera's extra pinhole views (cube-map faces)."""
    return f"{camera_name}/view{index}"


def camera_light_name(camera_name: str) -> str:
    """MJCF name of the light that stands in for the headlight of a multi-view camera."""
    return f"{camera_name}/headlight"


def _view_camera(name: str, world_from_camera: F64, view: View) -> str:
    """A MuJoCo camera with the view's pose and intrinsics (MuJoCo's principal point is the
    offset of the image centre from OpenCV's, in pixels)."""
    world_from_mjcam = world_from_camera[:3, :3] @ view.camera_from_view @ OPTICAL_FROM_MJCAMERA
    xyaxes = np.concatenate([world_from_mjcam[:, 0], world_from_mjcam[:, 1]])
    w, h = view.width, view.height
    principal = ((w - 1) / 2 - view.cx, (h - 1) / 2 - view.cy)
    return (
        f'  <camera name={quoteattr(name)} pos="{_vec(world_from_camera[:3, 3])}" '
        f'xyaxes="{_vec(xyaxes)}" resolution="{w} {h}" sensorsize="{_vec((w * 1e-6, h * 1e-6))}" '
        f'focalpixel="{_vec((view.focal_px, view.focal_px))}" '
        f'principalpixel="{_vec(principal)}"/>'
    )


def build_mjcf(
    scenario: ScenarioSpec, *, offscreen_size: tuple[int, int],
    views: dict[str, tuple[View, ...]] | None = None,
) -> str:
    """MJCF text of the scenario's scene; ``offscreen_size`` is the largest render (W, H);
    ``views`` adds each named camera's pinhole views (``view_camera_name``)."""
    width, height = offscreen_size
    circles = any(t.kind in ("circles", "acircles") for t in scenario.targets)
    parts = [
        f'<mujoco model={quoteattr("camlog_" + scenario.name)}>',
        '<compiler angle="radian"/>',
        '<option gravity="0 0 0"/>',
        '<statistic extent="1" center="0 0 0.25"/>',
        "<visual>",
        f'  <global offwidth="{width}" offheight="{height}"/>',
        '  <quality offsamples="8"/>' if not circles else
        f'  <quality offsamples="8" numslices="{CIRCLE_SLICES}"/>',
        f'  <headlight ambient="{_vec(HEADLIGHT_AMBIENT)}" diffuse="{_vec(HEADLIGHT_DIFFUSE)}" '
        'specular="0 0 0"/>',
        '  <map znear="0.005" zfar="20"/>',
        "</visual>",
        "<asset>",
        '  <material name="white" rgba="0.93 0.93 0.93 1" specular="0" shininess="0"/>',
        '  <material name="black" rgba="0.03 0.03 0.03 1" specular="0" shininess="0"/>',
        '  <material name="ground" rgba="0.55 0.57 0.6 1" specular="0" shininess="0"/>',
    ]
    for target in scenario.targets:
        if target.kind == "box":
            parts.append(
                f'  <material name="{target.name}_mat" rgba="{_vec(target.rgba)}" '
                'specular="0" shininess="0"/>'
            )
    parts += [
        "</asset>",
        "<worldbody>",
        '  <light directional="true" pos="0 0 3" dir="0 0 -1" diffuse="0.35 0.35 0.35" '
        'specular="0 0 0" castshadow="false"/>',
        '  <geom name="ground" type="plane" size="2 2 0.01" material="ground"/>',
    ]
    for camera in scenario.cameras:
        world_from_mjcam = camera.world_from_camera[:3, :3] @ OPTICAL_FROM_MJCAMERA
        xyaxes = np.concatenate([world_from_mjcam[:, 0], world_from_mjcam[:, 1]])
        parts.append(
            f'  <camera name={quoteattr(camera.name)} '
            f'pos="{_vec(camera.world_from_camera[:3, 3])}" xyaxes="{_vec(xyaxes)}" fovy="30"/>'
        )
        camera_views = (views or {}).get(camera.name, ())
        if camera_views:
            parts.append(
                f'  <light name={quoteattr(camera_light_name(camera.name))} directional="false" '
                f'pos="{_vec(camera.world_from_camera[:3, 3])}" '
                f'dir="{_vec(camera.world_from_camera[:3, 2])}" cutoff="180" exponent="0" '
                'attenuation="1 0 0" '
                f'ambient="{_vec(HEADLIGHT_AMBIENT)}" diffuse="{_vec(HEADLIGHT_DIFFUSE)}" '
                'specular="0 0 0" castshadow="false" active="false"/>'
            )
        for index, view in enumerate(camera_views):
            parts.append(_view_camera(view_camera_name(camera.name, index),
                                      camera.world_from_camera, view))
    for target in scenario.targets:
        pose = target.motion.world_from_target
        quat = quat_xyzw_from_rotation(pose[:3, :3])
        parts.append(
            f'  <body name={quoteattr(target.name)} mocap="true" pos="{_vec(pose[:3, 3])}" '
            f'quat="{_vec([quat[3], *quat[:3]])}">'
        )
        geoms = (
            target_geoms(target)
            if target.kind in PLANAR_KINDS
            else [f'<geom type="box" size="{_vec(target.size_m / 2)}" '
                  f'material="{target.name}_mat"/>']
        )
        no_contact = '<geom contype="0" conaffinity="0" '
        parts += ["    " + g.replace("<geom ", no_contact) for g in geoms]
        parts.append("  </body>")
    parts += ["</worldbody>", "</mujoco>"]
    return "\n".join(parts)
