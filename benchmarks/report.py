"""One machine-readable line per benchmark result, collected by ``python -m benchmarks``."""

from __future__ import annotations

import json

PREFIX = "BENCHMARK "


def emit(name: str, *, baseline: str, baseline_value: float, measured: str,
         measured_value: float, unit: str, ratio: float, target: str) -> None:
    """Print a result: a camlog figure, its in-run baseline, their ratio and the target."""
    print(PREFIX + json.dumps({
        "name": name, "baseline": baseline, "baseline_value": round(baseline_value, 3),
        "measured": measured, "measured_value": round(measured_value, 3), "unit": unit,
        "ratio": round(ratio, 3), "target": target,
    }), flush=True)
