"""rerun export of camlog logs: entity layout, overlays, default blueprint, recording sinks.

Names are loaded from their modules on first use: :mod:`rerun_export.paths` (where a view
writes) is usable before the rerun SDK, which the other modules import, is loaded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from replay.lazy import lazy_names

from .errors import RerunExportError, ViewerError

if TYPE_CHECKING:
    from .logger import LoggerOptions, SceneLogger
    from .paths import default_output
    from .scene import ScenePlan, plan_scene
    from .sink import RecordingSink
    from .view import ViewResult, view_logs

#: public name -> the module that defines it
_MODULES = {
    **dict.fromkeys(("LoggerOptions", "SceneLogger"), ".logger"),
    "default_output": ".paths",
    **dict.fromkeys(("ScenePlan", "plan_scene"), ".scene"),
    "RecordingSink": ".sink",
    **dict.fromkeys(("ViewResult", "view_logs"), ".view"),
}


#: load a public name from its module on first use
__getattr__ = lazy_names(__name__, _MODULES, globals())


__all__ = [
    "LoggerOptions",
    "RecordingSink",
    "RerunExportError",
    "SceneLogger",
    "ScenePlan",
    "ViewResult",
    "ViewerError",
    "default_output",
    "plan_scene",
    "view_logs",
]
