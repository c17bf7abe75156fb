"""One machine-readable line per benchmark result, collected by ``python -m benchmarks``."""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from typing import Any

PREFIX = "BENCHMARK "
#: the results this process emitted, in order (what ``--write-docs`` writes)
RESULTS: list[dict[str, Any]] = []
#: the table of docs/benchmarks.md that holds every benchmark's in-run ratio
SUMMARY = "summary"


def emit(name: str, *, baseline: str, baseline_value: float, measured: str,
         measured_value: float, unit: str, ratio: float, target: str) -> None:
    """Print a result: a camlog figure, its in-run baseline, their ratio and the target."""
    result = {
        "name": name, "baseline": baseline, "baseline_value": round(baseline_value, 3),
        "measured": measured, "measured_value": round(measured_value, 3), "unit": unit,
        "ratio": round(ratio, 3), "target": target,
    }
    RESULTS.append(result)
    print(PREFIX + json.dumps(result), flush=True)


def figure(value: float) -> str:
    """``value`` to three significant digits, never in exponent form (1736, 30.3, 0.650)."""
    if value == 0 or not math.isfinite(value):
        return f"{value:g}"
    return f"{value:.{max(0, 2 - math.floor(math.log10(abs(value))))}f}"


def summary_row(benchmark: str, result: dict[str, Any]) -> list[str]:
    """The cells of one result in the docs' summary table."""
    unit = result["unit"]
    return [f"`{benchmark}`: {result['name']}",
            f"{result['baseline']} {figure(result['baseline_value'])} {unit}",
            f"{result['measured']} {figure(result['measured_value'])} {unit}",
            f"{result['ratio']:.2f}", result["target"]]


def write_summary_rows(benchmark: str, args: argparse.Namespace) -> None:
    """With ``--write-docs``: this run's results as the rows of ``benchmark`` in the docs'
    summary table (the other benchmarks' rows stay)."""
    if not args.write_docs or not RESULTS:
        return
    from .docs import markdown_row, write_rows

    write_rows(SUMMARY, f"`{benchmark}`:", [markdown_row(summary_row(benchmark, r))
                                            for r in RESULTS])


#: VmHWM, not ru_maxrss: ru_maxrss survives fork + exec, so a child would report the
#: benchmark's own (MuJoCo-sized) peak; VmHWM belongs to the new address space.
_PEAK_RSS = (
    "import re, sys\n"
    "from camlog.cli import main\n"
    "code = main(sys.argv[1:])\n"
    "status = open('/proc/self/status').read()\n"
    "print(re.search(r'VmHWM:\\s*(\\d+)', status).group(1))\n"
    "sys.exit(code)\n"
)


def cli_peak_rss_mb(argv: list[str]) -> float:
    """Peak resident memory (MB) of ``camlog ARGV…`` run in a fresh process."""
    done = subprocess.run([sys.executable, "-c", _PEAK_RSS, *argv], check=True,
                          capture_output=True, text=True)
    return int(done.stdout.strip().splitlines()[-1]) / 1024
