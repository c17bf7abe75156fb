"""The radial order chosen from the views (camlog's default) against k1 k2 (the default
before it), over many seeds.

Each case of :mod:`benchmarks.vs_mrcal` but the fisheye (whose model has no ladder) is
calibrated from the same cached recording (``NAME_SEED_10s.mcap``, recorded when missing)
with the flags a user gives, without any lens model: with ``-k 2`` (``k1 k2``: plumb_bob k1
k2, p1 p2 when the likelihood-ratio test finds them) and as they are (``chosen``: the order
chosen per camera among plumb_bob k1 k2, k1 k2 k3 and rational_polynomial k1..k6); the
ChArUco case, whose flags name its rational lens, also with them (``model named``). It
prints, per case and figure, the median and the 80th percentile over the seeds of |error|
against the simulator's truth (as :mod:`benchmarks.vs_mrcal` scores it), how often each
order was chosen and the median wall time of the runs.

    python -m benchmarks.model_order [--seeds 13] [--cases heldout,stereo,charuco,moving_blur]
        [--cache DIR]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from camlog.calibrate.flow import CalibrationRun
from camlog.errors import CalibrationError
from processors.calibration.model_order import order_label

from .calibrate_speed import Case, calibrate
from .calibration_truth import camlog_accuracy
from .spread import Results, table
from .vs_mrcal import CASES as VS_MRCAL_CASES
from .vs_mrcal import add_seed_arguments, check_seed_arguments, default_flags, recording

TOOLS = ["k1 k2", "model named", "chosen"]
CASES = [c for c in VS_MRCAL_CASES if "--model fisheye" not in c.flags]
CASE_NAMES = [c.name for c in CASES]


def without_model(flags: str) -> str:
    """A case's default flags without a lens model (camlog's default: plumb_bob k1 k2)."""
    words = default_flags(flags).split()
    if "--model" in words:
        at = words.index("--model")
        del words[at:at + 2]
    return " ".join(words)


def runs(flags: str) -> dict[str, str]:
    """The flags of every run of a case: k1 k2, the lens model its flags name (if any) and
    the order chosen."""
    out = {"k1 k2": f"{without_model(flags)} -k 2", "model named": default_flags(flags),
           "chosen": without_model(flags)}
    if out["model named"] == out["chosen"]:
        del out["model named"]
    return out


def chosen_orders(run: CalibrationRun) -> list[str]:
    """The order each camera of a run that chose it was calibrated with."""
    return [order_label(c.solution.order.options) if c.solution.order is not None else "?"
            for c in run.cameras]


def steps_text(run: CalibrationRun) -> str:
    """Every camera's rungs of a run that chose its order: gain (%) and p of each."""
    return " | ".join(", ".join(f"{100 * s.gain:+.1f} % p {s.p_value:.2g}" for s in order.steps)
                      for c in run.cameras if (order := c.solution.order) is not None)


def compare(cases: list[Case], seeds: range, *, cache: Path) -> None:
    """Calibrate every case and seed both ways; print each seed's line, then the table."""
    results: Results = {}
    failures: dict[tuple[str, str], int] = {}
    chosen: dict[str, Counter[str]] = {}
    wall_s: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            for case in cases:
                path = recording(case, seed, cache, None)
                line = []
                for tool, flags in runs(case.flags).items():
                    try:
                        run = calibrate(path, flags, Path(tmp) / tool, report=False)
                    except CalibrationError as err:
                        failures[case.name, tool] = failures.get((case.name, tool), 0) + 1
                        print(f"  {case.name} seed {seed}: {tool} failed: {err}", flush=True)
                        continue
                    accuracy = camlog_accuracy(run)
                    results.setdefault(case.name, {}).setdefault(tool, []).append(accuracy)
                    wall_s.setdefault((case.name, tool), []).append(run.wall_s)
                    line.append(f"{tool} {max(accuracy.max_difference_px):.3f}")
                    if tool == "chosen":
                        orders = chosen_orders(run)
                        chosen.setdefault(case.name, Counter()).update(orders)
                        line.append(f"({', '.join(orders)}; {steps_text(run)}; "
                                    f"{run.wall_s:.1f} s)")
                print(f"  {case.name} seed {seed}: max projection px " + " ".join(line),
                      flush=True)
    print("\n".join(table(results, TOOLS, failures)))
    for case in cases:
        counts = ", ".join(f"{order} {n}" for order, n in
                           chosen.get(case.name, Counter()).most_common())
        times = ", ".join(f"{t} {statistics.median(wall_s[case.name, t]):.1f}"
                          for t in TOOLS if (case.name, t) in wall_s)
        print(f"{case.name}: chosen per camera: {counts}; median wall s: {times}")


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_seed_arguments(parser, seeds=13, case_names=CASE_NAMES)
    args = parser.parse_args(argv)
    check_seed_arguments(parser, args, CASE_NAMES)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    compare([c for c in CASES if c.name in args.cases.split(",")], range(args.seeds),
            cache=args.cache)
    print(f"load average {os.getloadavg()[0]:.1f} at the end", flush=True)


if __name__ == "__main__":
    main()
