"""Exception tree of the recorder."""

from __future__ import annotations


class RecorderError(Exception):
    """Base of every error raised by :mod:`recorder`."""


class ScenarioError(RecorderError):
    """A scenario name is unknown or a spec file is invalid."""


class RenderError(RecorderError):
    """MuJoCo could not render (no GL backend, bad model)."""
