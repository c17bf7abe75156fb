"""One machine-readable line per benchmark result, collected by ``python -m benchmarks``."""

from __future__ import annotations

import json
import subprocess
import sys

PREFIX = "BENCHMARK "


def emit(name: str, *, baseline: str, baseline_value: float, measured: str,
         measured_value: float, unit: str, ratio: float, target: str) -> None:
    """Print a result: a camlog figure, its in-run baseline, their ratio and the target."""
    print(PREFIX + json.dumps({
        "name": name, "baseline": baseline, "baseline_value": round(baseline_value, 3),
        "measured": measured, "measured_value": round(measured_value, 3), "unit": unit,
        "ratio": round(ratio, 3), "target": target,
    }), flush=True)


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
