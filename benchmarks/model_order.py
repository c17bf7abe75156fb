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

With ``--warp`` it measures the board warp's choice instead: every case with its flags as
they are, once with ``--board-warp off`` (``flat``) and once as given (``warp auto``: the
warp cross-validated, camlog's default); the simulated boards are flat, so ``warp auto``
should hold them flat and change no figure.

    python -m benchmarks.model_order [--seeds 13] [--cases heldout,stereo,charuco,moving_blur]
        [--cache DIR] [--warp]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
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
WARP_TOOLS = ["flat", "warp auto"]
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


def warp_runs(flags: str) -> dict[str, str]:
    """The flags of the board warp's runs: held flat, and cross-validated (the default)."""
    return {"flat": f"{default_flags(flags)} --board-warp off",
            "warp auto": default_flags(flags)}


def warp_chosen(run: CalibrationRun) -> list[str]:
    """Whether the run's board warp was estimated, and its size in mm."""
    estimate = run.solved.joint.board_warp_m
    if estimate is None:
        return ["flat"]
    return ["warp " + ",".join(f"{1000 * w:.2f}" for w in estimate[0]) + " mm"]


def warp_steps(run: CalibrationRun) -> str:
    """The warp's cross-validation: gain (%) and p."""
    choice = run.solved.joint.warp_choice
    if choice is None or choice.why_not is not None:
        return "not cross-validated"
    return f"{100 * choice.gain:+.1f} % p {choice.p_value:.2g}"


@dataclass(frozen=True)
class Comparison:
    """What is compared: the runs' names (the last one the choice), their flags per case's
    flags, and what the choosing run chose and on what evidence."""

    tools: list[str]
    runs: Callable[[str], dict[str, str]]
    chosen: Callable[[CalibrationRun], list[str]]
    steps: Callable[[CalibrationRun], str]


def chosen_orders(run: CalibrationRun) -> list[str]:
    """The order each camera of a run that chose it was calibrated with."""
    return [order_label(c.order.options) if c.order is not None else "?"
            for c in run.cameras]


def steps_text(run: CalibrationRun) -> str:
    """Every camera's rungs of a run that chose its order: gain (%) and p of each."""
    return " | ".join(", ".join(f"{100 * s.gain:+.1f} % p {s.p_value:.2g}" for s in order.steps)
                      for c in run.cameras if (order := c.order) is not None)


ORDER = Comparison(TOOLS, runs, chosen_orders, steps_text)
WARP = Comparison(WARP_TOOLS, warp_runs, warp_chosen, warp_steps)


def compare(cases: list[Case], seeds: range, *, cache: Path,
            comparison: Comparison = ORDER) -> None:
    """Calibrate every case and seed every way; print each seed's line, then the table."""
    tools, last = comparison.tools, comparison.tools[-1]
    results: Results = {}
    failures: dict[tuple[str, str], int] = {}
    chosen: dict[str, Counter[str]] = {}
    wall_s: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            for case in cases:
                path = recording(case, seed, cache, None)
                line = []
                for tool, flags in comparison.runs(case.flags).items():
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
                    if tool == last:
                        orders = comparison.chosen(run)
                        chosen.setdefault(case.name, Counter()).update(orders)
                        line.append(f"({', '.join(orders)}; {comparison.steps(run)}; "
                                    f"{run.wall_s:.1f} s)")
                print(f"  {case.name} seed {seed}: max projection px " + " ".join(line),
                      flush=True)
    print("\n".join(table(results, tools, failures)))
    for case in cases:
        counts = ", ".join(f"{order} {n}" for order, n in
                           chosen.get(case.name, Counter()).most_common())
        times = ", ".join(f"{t} {statistics.median(wall_s[case.name, t]):.1f}"
                          for t in tools if (case.name, t) in wall_s)
        print(f"{case.name}: chosen: {counts}; median wall s: {times}")


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_seed_arguments(parser, seeds=13, case_names=CASE_NAMES)
    parser.add_argument("--warp", action="store_true",
                        help="compare the board held flat with its warp cross-validated")
    args = parser.parse_args(argv)
    check_seed_arguments(parser, args, CASE_NAMES)
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores", flush=True)
    compare([c for c in CASES if c.name in args.cases.split(",")], range(args.seeds),
            cache=args.cache, comparison=WARP if args.warp else ORDER)
    print(f"load average {os.getloadavg()[0]:.1f} at the end", flush=True)


if __name__ == "__main__":
    main()
