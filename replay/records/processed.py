"""The record ``camlog process`` writes on ``/camlog/processed``: what each output topic is.

Each run that writes into a log adds one message; a log processed twice (say, the left
camera, then the right one) holds two, and a later record wins for a topic both name.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from ..display import Display
from .base import JsonRecord

__all__ = ["ProcessedOutput", "ProcessedOutputs", "outputs_by_topic"]


@dataclass(frozen=True)
class ProcessedOutput:
    """One output topic: computed by ``processor`` (its output ``output``) from the image
    topic ``source``, shown as ``display`` (a :class:`~replay.display.Display` value) under
    the camera entity's ``entity`` path (the series name for time series), titled
    ``label``."""

    topic: str
    source: str
    processor: str
    output: str
    msgtype: str
    display: str
    entity: str
    label: str

    @property
    def shown_as(self) -> Display | None:
        """The display, or None when this camlog does not know it (a newer writer's)."""
        try:
            return Display(self.display)
        except ValueError:
            return None


@dataclass(frozen=True)
class ProcessedOutputs(JsonRecord):
    """The outputs of one run and the options of its processors (JSON values)."""

    what = "processed-outputs record"

    outputs: list[ProcessedOutput]
    options: dict[str, Any] = field(default_factory=dict)
    version: str = ""


def outputs_by_topic(records: Iterable[ProcessedOutputs]) -> dict[str, ProcessedOutput]:
    """Output topic -> its declaration over several records (a later record wins)."""
    return {o.topic: o for record in records for o in record.outputs}
