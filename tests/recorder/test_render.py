"""The scene renderer's start-up errors: a GL failure is one RenderError, Ctrl-C stays Ctrl-C."""

from __future__ import annotations

import ctypes
from typing import Any

import pytest

from recorder.errors import RenderError
from recorder.optics import plan_optics
from recorder.render import SceneRenderer, _import_mujoco
from recorder.scenario import load_scenario


def _failing_renderer(error: Exception) -> Any:
    def make(*_args: Any, **_kwargs: Any) -> Any:
        raise error
    return make


@pytest.mark.slow
@pytest.mark.parametrize("error, expected", [
    # ctypes (PyOpenGL's EGL calls) wraps a Ctrl-C during argument conversion
    (ctypes.ArgumentError("argument 2: KeyboardInterrupt: "), KeyboardInterrupt),
    (RuntimeError("gladLoadGL error"), RenderError),
    (ctypes.ArgumentError("argument 2: TypeError: wrong type"), RenderError),
], ids=["ctrl-c inside ctypes", "no GL", "a ctypes error"])
def test_a_gl_start_up_failure_is_a_render_error_unless_it_was_ctrl_c(
        monkeypatch: pytest.MonkeyPatch, error: Exception,
        expected: type[BaseException]) -> None:
    scenario = load_scenario("red_block")
    optics = [plan_optics(camera.model, 1) for camera in scenario.cameras]
    mujoco = _import_mujoco()  # as the renderer loads it: MUJOCO_GL chosen first
    monkeypatch.setattr(mujoco, "Renderer", _failing_renderer(error))
    with pytest.raises(expected) as raised:
        SceneRenderer(scenario, optics)  # type: ignore[arg-type]
    if expected is RenderError:
        assert "no working GL backend for MuJoCo" in str(raised.value)
