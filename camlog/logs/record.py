"""``camlog record``: a scenario, with the request's overrides, simulated into a log."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from replay.atomic import refuse_existing

from ..requests.record import RecordRequest

if TYPE_CHECKING:
    from recorder.record import RecordResult
    from recorder.scenario import ScenarioSpec

__all__ = ["Recorded", "record_log"]


@dataclass(frozen=True)
class Recorded:
    """The scenario as it was resolved, and what its recording wrote."""

    scenario: ScenarioSpec
    result: RecordResult


def record_log(request: RecordRequest) -> Recorded:
    """Record the request's scenario into ``output`` (default recordings/SCENARIO.mcap);
    an existing output is refused before the recorder's libraries load."""
    if request.output is not None:
        refuse_existing(request.output, overwrite=request.overwrite)
    from recorder.record import record
    from recorder.scenario import load_scenario

    scenario = load_scenario(request.scenario, request.overrides())
    output = request.output or Path("recordings") / f"{scenario.name}.mcap"
    refuse_existing(output, overwrite=request.overwrite)
    if request.output is None:
        output.parent.mkdir(parents=True, exist_ok=True)
    result = record(scenario, output, fmt=request.format, overwrite=request.overwrite,
                    progress=request.progress, compression=request.compression)
    return Recorded(scenario, result)
