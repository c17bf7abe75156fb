"""Run every benchmark, each in its own process, and print one table of in-run ratios.

    python -m benchmarks            # full runs (several minutes on 2 cores)
    python -m benchmarks --quick    # short recordings: a smoke test of every benchmark
    python -m benchmarks --write-docs   # and write each one's rows into docs/benchmarks.md
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

from .docs import add_write_docs
from .report import PREFIX

#: module -> (full arguments, quick arguments)
BENCHMARKS: dict[str, tuple[list[str], list[str]]] = {
    "record_fps": ([], ["--frames", "150", "--repeats", "1"]),
    "process_fps": ([], ["--frames", "100", "--repeats", "1"]),
    "decode_fps": ([], ["--frames", "10", "--repeats", "1"]),
    "video_size": ([], ["--duration", "1"]),
    "calibrate_speed": ([], ["--quick"]),
    "view_fps": ([], ["--duration", "5"]),
    "batch_speedup": ([], ["--frames", "90"]),
    "batch_ray": ([], ["--frames", "90"]),
    "demo_time": ([], ["--duration", "2"]),
    "peers": (["--growth", "4,40,400", "--memory"],
              ["--runs", "1", "--duration", "1", "--view-duration", "2"]),
    "check_speed": ([], ["--duration", "2", "--repeats", "1"]),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short runs (smoke test)")
    parser.add_argument("--only", nargs="+", choices=sorted(BENCHMARKS), help="run these only")
    add_write_docs(parser)
    args = parser.parse_args()
    if args.quick and args.write_docs:
        parser.error("--write-docs writes measured figures: not with --quick")
    rows = []
    for module, (full, quick) in BENCHMARKS.items():
        if args.only and module not in args.only:
            continue
        started = time.perf_counter()
        print(f"--- benchmarks.{module}", flush=True)
        done = subprocess.run([sys.executable, "-m", f"benchmarks.{module}",
                               *(quick if args.quick else full),
                               *(["--write-docs"] if args.write_docs else [])],
                              capture_output=True, text=True,
                              check=False)
        sys.stdout.write(done.stdout)
        if done.returncode != 0:
            sys.stdout.write(done.stderr[-2000:])
            rows.append({"name": module, "error": f"exit {done.returncode}"})
            continue
        found = [json.loads(line[len(PREFIX):]) for line in done.stdout.splitlines()
                 if line.startswith(PREFIX)]
        rows += found or [{"name": module, "error": "no result line"}]
        print(f"    ({time.perf_counter() - started:.0f} s)", flush=True)
    print()
    header = f"{'benchmark':44} {'baseline':>30} {'camlog':>30} {'ratio':>7}  target"
    print(header)
    print("-" * len(header))
    for r in rows:
        if "error" in r:
            print(f"{r['name']:44} {'':>30} {'':>30} {'':>7}  FAILED ({r['error']})")
            continue
        base = f"{r['baseline']} {r['baseline_value']:g} {r['unit']}"
        mine = f"{r['measured']} {r['measured_value']:g} {r['unit']}"
        print(f"{r['name']:44} {base:>30} {mine:>30} {r['ratio']:7.2f}  {r['target']}")
    if any("error" in r for r in rows):
        sys.exit(1)


if __name__ == "__main__":
    main()
