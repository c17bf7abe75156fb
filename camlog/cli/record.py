"""``camlog record``: simulate a scenario and write its camera log."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.record import RecordRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``record`` arguments."""
    add_request(p, RecordRequest)


def run(args: argparse.Namespace) -> int:
    """Record the scenario and print what was written."""
    from ..logs.record import record_log

    recorded = record_log(request_from_args(RecordRequest, args))
    scenario, result = recorded.scenario, recorded.result
    frames = ", ".join(f"{name} {n}" for name, n in result.frames.items())
    drops = {n: len(d) for n, d in result.dropped.items() if d}
    dropped = f", dropped {drops}" if drops else ""
    print(f"recorded {scenario.name} (seed {scenario.seed}): {frames} frames{dropped} "
          f"in {result.wall_s:.1f} s ({result.fps:.0f} frames/s)")
    for drift in scenario.drifts:
        print(f"drift: {drift.camera} {drift.axis} {drift.degrees:+g}° from {drift.start_s:g} s")
    for latency in scenario.latencies:
        since = f" from {latency.start_s:g} s" if latency.start_s else ""
        print(f"latency: {latency.camera} stamped {latency.latency_ms:+g} ms from its "
              f"exposures{since}")
    print(f"wrote {result.path} ({result.storage})")
    return 0
