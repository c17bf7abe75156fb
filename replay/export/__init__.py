"""rerun export of camlog logs: entity layout, overlays, default blueprint, recording sinks."""

from .logger import LoggerOptions, SceneLogger
from .scene import ScenePlan, plan_scene
from .sink import RecordingSink, default_output
from .view import ViewResult, view_logs

__all__ = [
    "LoggerOptions",
    "RecordingSink",
    "SceneLogger",
    "ScenePlan",
    "ViewResult",
    "default_output",
    "plan_scene",
    "view_logs",
]
