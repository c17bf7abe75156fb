"""Headless MuJoCo rendering (EGL by default) of a scenario's cameras."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from replay.geometry import quat_xyzw_from_rotation
from replay.messages import F64

from .errors import RenderError
from .optics import Optics
from .scenario import Scenario
from .scene import build_mjcf


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
    """Owns the MuJoCo model, one renderer per render size, and the target mocap poses."""

    def __init__(self, scenario: Scenario, optics: list[Optics]) -> None:
        self.mujoco = _import_mujoco()
        mj = self.mujoco
        width = max(o.render_width for o in optics)
        height = max(o.render_height for o in optics)
        self.xml = build_mjcf(scenario, offscreen_size=(width, height))
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
        for o in optics:
            size = (o.render_width, o.render_height)
            if size not in self._renderers:
                try:
                    self._renderers[size] = mj.Renderer(self.model, o.render_height, o.render_width)
                except Exception as err:
                    raise RenderError(
                        f"no working GL backend for MuJoCo (MUJOCO_GL={gl_backend()}): "
                        f"{_line(err)}; install Mesa EGL (libegl1, libgl1) or set MUJOCO_GL"
                    ) from None
        mj.mj_forward(self.model, self.data)

    def set_poses(self, world_from_targets: list[F64]) -> None:
        """Move every target (mocap body) and update kinematics."""
        for mocap, pose in zip(self._mocap, world_from_targets, strict=True):
            q = quat_xyzw_from_rotation(pose[:3, :3])
            self.data.mocap_pos[mocap] = pose[:3, 3]
            self.data.mocap_quat[mocap] = [q[3], q[0], q[1], q[2]]
        self.mujoco.mj_kinematics(self.model, self.data)

    def render(self, camera_index: int) -> np.ndarray:
        """Ideal render ``(Hr, Wr, 3)`` uint8 of one camera at the current poses."""
        o = self.optics[camera_index]
        self.model.cam_fovy[camera_index] = o.fovy_deg
        renderer = self._renderers[(o.render_width, o.render_height)]
        renderer.update_scene(self.data, camera=self.camera_names[camera_index])
        return np.asarray(renderer.render())

    def close(self) -> None:
        """Release every camera's GL renderer."""
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers.clear()
