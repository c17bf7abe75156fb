"""Headless MuJoCo rendering (EGL by default) of a scenario's cameras."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from replay.geometry import OPTICAL_FROM_MJCAMERA, quat_xyzw_from_rotation
from replay.messages import F64

from .errors import RenderError
from .multiview import CameraOptics
from .optics import Optics
from .scenario import ScenarioSpec
from .scene import build_mjcf, camera_light_name, view_camera_name


def _mj_quat(rotation: F64) -> list[float]:
    """MuJoCo's quaternion (w, x, y, z) of a rotation (3, 3)."""
    q = quat_xyzw_from_rotation(rotation)
    return [float(q[3]), float(q[0]), float(q[1]), float(q[2])]


def _import_mujoco() -> Any:
    os.environ.setdefault("MUJOCO_GL", "egl")
    try:
        import mujoco
    except Exception as err:  # MuJoCo raises RuntimeError/ImportError for GL problems
        raise RenderError(
            f"cannot load MuJoCo with MUJOCO_GL={os.environ['MUJOCO_GL']}: {_line(err)}"
        ) from None
    return mujoco


def _line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else type(err).__name__


def gl_backend() -> str:
    """The GL backend MuJoCo uses (``MUJOCO_GL``)."""
    return os.environ.get("MUJOCO_GL", "egl")


class SceneRenderer:
    """Owns the MuJoCo model, its renderers (one per pinhole render size, one for every
    multi-view camera's views) and the target mocap poses."""

    def __init__(self, scenario: ScenarioSpec, optics: list[CameraOptics]) -> None:
        self.mujoco = _import_mujoco()
        mj = self.mujoco
        sizes = {size for o in optics for size in o.render_sizes}
        width = max(w for w, _ in sizes)
        height = max(h for _, h in sizes)
        views = {c.name: o.views for c, o in zip(scenario.cameras, optics, strict=True)
                 if not isinstance(o, Optics)}
        self.xml = build_mjcf(scenario, offscreen_size=(width, height), views=views)
        try:
            self.model = mj.MjModel.from_xml_string(self.xml)
        except Exception as err:
            raise RenderError(f"cannot build the MuJoCo scene: {_line(err)}") from None
        self.data = mj.MjData(self.model)
        self.optics = optics
        self.camera_names = [c.name for c in scenario.cameras]
        self._mocap = [
            int(self.model.body(t.name).mocapid[0]) for t in scenario.targets
        ]
        self._renderers: dict[tuple[int, int], Any] = {}
        self._views: ViewRenderer | None = None
        size = (0, 0)
        try:
            for o in optics:
                if isinstance(o, Optics):
                    size = (o.render_width, o.render_height)
                    if size not in self._renderers:
                        self._renderers[size] = mj.Renderer(self.model, size[1], size[0])
                elif self._views is None:
                    self._views = ViewRenderer(mj, self.model)
        except Exception as err:
            self.close()
            if _interrupted(err):
                raise KeyboardInterrupt from None
            if "framebuffer" in str(err).lower() and max(size) > 2048:
                raise RenderError(
                    f"cannot render {size[0]}x{size[1]} images (each camera's size times its "
                    f"supersampling): more than MuJoCo's GL framebuffer holds ({_line(err)}); "
                    "use a smaller --resolution or --supersample") from None
            raise RenderError(
                f"no working GL backend for MuJoCo (MUJOCO_GL={gl_backend()}): "
                f"{_line(err)}; install Mesa EGL (libegl1, libgl1) or set MUJOCO_GL"
            ) from None
        mj.mj_forward(self.model, self.data)

    def set_poses(self, world_from_targets: list[F64]) -> None:
        """Move every target (mocap body) and update kinematics."""
        for mocap, pose in zip(self._mocap, world_from_targets, strict=True):
            self.data.mocap_pos[mocap] = pose[:3, 3]
            self.data.mocap_quat[mocap] = _mj_quat(pose[:3, :3])
        self.mujoco.mj_kinematics(self.model, self.data)

    def turn_camera(self, camera_index: int, world_from_camera: F64) -> None:
        """Turn a camera (its pinhole view, or every view and the light of a multi-view
        camera) to the optical frame ``world_from_camera`` (4, 4) (its position unchanged)."""
        name = self.camera_names[camera_index]
        o = self.optics[camera_index]
        world_from_optical = world_from_camera[:3, :3]
        if isinstance(o, Optics):
            turned = {name: world_from_optical @ OPTICAL_FROM_MJCAMERA}
        else:
            turned = {view_camera_name(name, i): world_from_optical @ view.camera_from_view
                      @ OPTICAL_FROM_MJCAMERA for i, view in enumerate(o.views)}
            self.model.light_dir[self.model.light(camera_light_name(name)).id] = \
                world_from_optical[:, 2]
        for camera, world_from_mjcam in turned.items():
            self.model.cam_quat[self.model.camera(camera).id] = _mj_quat(world_from_mjcam)
        self.mujoco.mj_camlight(self.model, self.data)

    def render(self, camera_index: int) -> np.ndarray:
        """Ideal render ``(Hr, Wr, 3)`` uint8 of one camera at the current poses: its one
        pinhole view, or its views stacked into an atlas (``View.atlas_row``)."""
        o = self.optics[camera_index]
        name = self.camera_names[camera_index]
        if isinstance(o, Optics):
            self.model.cam_fovy[self.model.camera(name).id] = o.fovy_deg
            renderer = self._renderers[(o.render_width, o.render_height)]
            renderer.update_scene(self.data, camera=name)
            return np.asarray(renderer.render())
        atlas = np.zeros((sum(v.height for v in o.views), max(v.width for v in o.views), 3),
                         np.uint8)
        assert self._views is not None
        light = self.model.light(camera_light_name(name)).id
        self.model.vis.headlight.active = 0
        self.model.light_active[light] = 1
        try:
            for index, view in enumerate(o.views):
                camera = self.model.camera(view_camera_name(name, index)).id
                self._views.render(self.data, camera,
                                   atlas[view.atlas_row:view.atlas_row + view.height, :view.width])
        finally:
            self.model.vis.headlight.active = 1
            self.model.light_active[light] = 0
        return atlas

    def close(self) -> None:
        """Free every GL context."""
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()
        if self._views is not None:
            self._views.close()
            self._views = None


class ViewRenderer:
    """Renders a model's fixed cameras at any size up to its offscreen buffer, with one GL
    context (``mujoco.Renderer`` holds one context and buffer per image size)."""

    def __init__(self, mj: Any, model: Any) -> None:
        self.mujoco, self.model = mj, model
        width, height = model.vis.global_.offwidth, model.vis.global_.offheight
        self._gl: Any = None
        self._context: Any = None
        self._gl = mj.GLContext(width, height)
        self._gl.make_current()
        self._context = mj.MjrContext(model, mj.mjtFontScale.mjFONTSCALE_150.value)
        mj.mjr_setBuffer(mj.mjtFramebuffer.mjFB_OFFSCREEN.value, self._context)
        self._scene = mj.MjvScene(model=model, maxgeom=10000)
        self._option = mj.MjvOption()
        self._camera = mj.MjvCamera()
        self._camera.type = mj.mjtCamera.mjCAMERA_FIXED

    def render(self, data: Any, camera_id: int, out: np.ndarray) -> None:
        """Render camera ``camera_id`` into ``out`` ``(H, W, 3)`` uint8 (a camera whose
        intrinsics are given for a ``W x H`` image), top row first."""
        mj = self.mujoco
        height, width = out.shape[:2]
        self._gl.make_current()
        self._camera.fixedcamid = camera_id
        mj.mjv_updateScene(self.model, data, self._option, None, self._camera,
                           mj.mjtCatBit.mjCAT_ALL.value, self._scene)
        rect = mj.MjrRect(0, 0, width, height)
        mj.mjr_render(rect, self._scene, self._context)
        pixels = np.empty((height, width, 3), np.uint8)
        mj.mjr_readPixels(pixels, None, rect, self._context)
        out[:] = pixels[::-1]  # GL rows run bottom to top

    def close(self) -> None:
        """Free the GL context."""
        if self._context is not None:
            self._gl.make_current()
            self._context.free()
            self._context = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None


def _interrupted(err: BaseException) -> bool:
    """Whether ``err`` is a Ctrl-C in disguise: ctypes (under MuJoCo's GL bindings) turns a
    KeyboardInterrupt raised while it converts a call's arguments into an ArgumentError
    ("argument 2: KeyboardInterrupt: ")."""
    import ctypes

    return isinstance(err.__context__, KeyboardInterrupt) or (
        isinstance(err, ctypes.ArgumentError) and "KeyboardInterrupt" in str(err))
