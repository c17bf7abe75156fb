"""Drift checks over a fleet of logs, against the truth the simulator knows.

A fleet of short ``stereo_checkerboard`` logs (640x480, 10 Hz: the check looks at 5 pairs
per second) of different seeds, a tenth of them with one camera turned from a random
moment, about a random axis (pitch, roll or yaw), by a random size (0.05 to 0.5°, either
sign). Every log is checked by a batch ``check`` step (1 s windows) on the process engine
and again on a Ray instance the run starts on 127.0.0.1 (HOME and RAY_TMPDIR in a temporary
folder). Prints truth against what was found per log and the onset errors, and exits 1
unless: every pitch and roll drift is found, its onset within ``ONSET_S``; no clean log is
flagged; the two engines' ``check.csv`` files are identical. Yaw is reported, not required.

Logs are recorded into ``--cache`` (outside the repository, named by their inputs) and
reused.

    python -m benchmarks.fleet_check [--logs 50] [--seed 0] [--cache DIR]
    python -m benchmarks.fleet_check --sweep 3    # smallest drift found per axis
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from unittest import mock

import numpy as np

from .report import emit

DEFAULT_CACHE = Path.home() / ".cache" / "camlog" / "fleet_check"
SCENARIO, WIDTH, HEIGHT, RATE_HZ = "stereo_checkerboard", 640, 480, 10.0
#: log length, and the windows a drift leaves after it at least
DURATION_S, WINDOW_S, WINDOWS_AFTER = 8.0, 1.0, 3
#: drifts start between this moment and the last that leaves WINDOWS_AFTER windows
EARLIEST_S = 1.5
SIZES_DEG = (0.05, 0.5)
#: a found onset is within this of the true one
ONSET_S = 2.0
PIPELINE = f'[[steps]]\nrun = "check"\nwindow = {WINDOW_S}\n'


@dataclass(frozen=True)
class Drift:
    """One camera turned about one axis by ``degrees`` from ``start_s`` on."""

    camera: str
    axis: str
    degrees: float
    start_s: float

    def spec(self) -> dict[str, object]:
        """The scenario's ``[[drifts]]`` table."""
        return {"camera": self.camera, "axis": self.axis, "degrees": self.degrees,
                "start_s": self.start_s}


@dataclass(frozen=True)
class FleetLog:
    """One log of the fleet: its seed and its drift (None: clean)."""

    seed: int
    drift: Drift | None

    @property
    def name(self) -> str:
        """File name, from every input that shapes the recording."""
        base = f"{SCENARIO}-seed{self.seed}-{WIDTH}x{HEIGHT}-{RATE_HZ:g}hz-{DURATION_S:g}s"
        d = self.drift
        return base + (f"-{d.camera}-{d.axis}{d.degrees:+.3f}@{d.start_s:.2f}" if d else "") \
            + ".mcap"


def plan_fleet(count: int, *, drifted: int, seed: int,
               axes: tuple[str, ...] = ("pitch", "roll", "yaw")) -> list[FleetLog]:
    """``count`` logs of seeds ``seed * 1000 + i``, ``drifted`` of them (chosen at random)
    with a random drift: camera, moment, size and sign at random, the axes taken in turn
    (so that each is drawn) in a random order."""
    rng = np.random.default_rng(seed)
    chosen = rng.choice(count, size=drifted, replace=False).tolist()
    turns = [axes[i % len(axes)] for i in range(drifted)]
    order = rng.permutation(drifted).tolist()
    latest_s = DURATION_S - WINDOWS_AFTER * WINDOW_S
    fleet = []
    for index in range(count):
        drift = None
        if index in chosen:
            size = float(rng.uniform(*SIZES_DEG)) * float(rng.choice([-1.0, 1.0]))
            drift = Drift(str(rng.choice(["left", "right"])),
                          turns[order[chosen.index(index)]], round(size, 3),
                          round(float(rng.uniform(EARLIEST_S, latest_s)), 2))
        fleet.append(FleetLog(seed * 1000 + index, drift))
    return fleet


def record_fleet(fleet: list[FleetLog], cache: Path) -> list[Path]:
    """Each log's recording in ``cache``, rendered unless already there."""
    from recorder.record import record
    from recorder.scenario import load_scenario

    cache.mkdir(parents=True, exist_ok=True)
    paths = []
    for log in fleet:
        path = cache / log.name
        if not path.is_file():
            overrides: dict[str, object] = {
                "seed": log.seed, "duration_s": DURATION_S, "rate_hz": RATE_HZ,
                "width": WIDTH, "height": HEIGHT}
            if log.drift is not None:
                overrides["drifts"] = [log.drift.spec()]
            record(load_scenario(SCENARIO, overrides), path, progress=False)
        paths.append(path)
    return paths


@contextmanager
def temporary_home() -> Iterator[Path]:
    """HOME and RAY_TMPDIR in a temporary folder (Ray writes its token and sessions there),
    restored afterwards. Short: Ray's socket paths are limited."""
    home = Path(tempfile.mkdtemp(prefix="fh", dir="/tmp"))
    try:
        with mock.patch.dict(os.environ, HOME=str(home), RAY_TMPDIR=str(home / "tmp")):
            yield home
    finally:
        shutil.rmtree(home, ignore_errors=True)


@dataclass(frozen=True)
class Found:
    """What the check found in one log: its flagged onset (s; None: not flagged) and the
    median rotation over its flagged windows (degrees)."""

    onset_s: float | None
    rotation_deg: float


def check_fleet(paths: list[Path], out: Path, engine: str) -> dict[str, str]:
    """Run ``camlog batch`` with the ``check`` step over the logs on ``engine``, in a process
    of its own as a user would (a Ray instance lives and dies with it): each log's
    check.csv."""
    import subprocess

    from camlog.batch.run import log_name

    pipeline = out.parent / "fleet_check.toml"
    pipeline.parent.mkdir(parents=True, exist_ok=True)
    pipeline.write_text(PIPELINE)
    done = subprocess.run([sys.executable, "-m", "camlog", "batch", str(pipeline),
                           *map(str, paths), "-o", str(out), "-j", "2", "--engine", engine,
                           "--no-progress"], capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{engine}: camlog batch exited {done.returncode}: "
                           f"{(done.stderr.strip() or done.stdout.strip())[-2000:]}")
    return {p.name: next((out / log_name(p)).rglob("check.csv")).read_text() for p in paths}


def found_in(check_csv: str) -> Found:
    """The onset and rotation a log's check.csv shows."""
    rows = list(csv.DictReader(check_csv.splitlines()))
    flagged = [r for r in rows if r["flagged"] == "1"]
    onset = min((float(r["start_s"]) for r in flagged), default=None)
    rotations = [float(r["value"]) for r in flagged if r["metric"] == "rotation_deg"
                 and r["value"]]
    return Found(onset, float(np.median(rotations)) if rotations else math.nan)


def judge(fleet: list[FleetLog], found: list[Found]) -> tuple[list[str], list[str]]:
    """The table of truth against what was found, and the requirements that failed."""
    rows = [f"{'log':<12} {'truth':<32} {'found':<28} onset error"]
    failures = []
    for log, got in zip(fleet, found, strict=True):
        d = log.drift
        truth = f"{d.camera} {d.axis} {d.degrees:+.3f}° at {d.start_s:.2f} s" if d else "clean"
        seen = "clean" if got.onset_s is None else \
            f"from {got.onset_s:g} s, {got.rotation_deg:.3f}°"
        error = "" if d is None or got.onset_s is None else f"{got.onset_s - d.start_s:+.2f} s"
        rows.append(f"seed {log.seed:<7} {truth:<32} {seen:<28} {error}")
        if d is None and got.onset_s is not None:
            failures.append(f"seed {log.seed}: a clean log flagged")
        elif d is not None and d.axis != "yaw":
            if got.onset_s is None:
                failures.append(f"seed {log.seed}: {truth} not found")
            elif abs(got.onset_s - d.start_s) > ONSET_S:
                failures.append(f"seed {log.seed}: onset {got.onset_s:g} s for {truth}")
    return rows, failures


def run_fleet(fleet: list[FleetLog], cache: Path, work: Path
              ) -> tuple[list[Found], bool, dict[str, float]]:
    """Record, check on both engines; what was found, whether the engines agree, and each
    engine's wall time (s)."""
    import time

    paths = record_fleet(fleet, cache)
    csvs, wall = {}, {}
    with temporary_home():
        for engine in ("process", "ray"):
            started = time.perf_counter()
            csvs[engine] = check_fleet(paths, work / engine, engine)
            wall[engine] = time.perf_counter() - started
    found = [found_in(csvs["process"][p.name]) for p in paths]
    return found, csvs["process"] == csvs["ray"], wall


#: the sizes the sensitivity sweep tries per axis (degrees)
SWEEP_DEG = {"pitch": (0.01, 0.02, 0.05), "roll": (0.02, 0.03, 0.05), "yaw": (0.1, 0.25, 0.5)}
SWEEP_START_S = 3.0


def sweep(cache: Path, seeds: int) -> list[str]:
    """Smallest drifts found: each axis and size on the right camera from ``SWEEP_START_S``,
    over ``seeds`` seeds; one line per axis and size (found, onset errors)."""
    from camlog.check.flow import CheckOptions, check_drift

    lines = []
    for axis, sizes in SWEEP_DEG.items():
        for size in sizes:
            fleet = [FleetLog(900 + seed, Drift("right", axis, size, SWEEP_START_S))
                     for seed in range(seeds)]
            onsets = [check_drift(path, CheckOptions(window_s=WINDOW_S)).drifted_from_s()
                      for path in record_fleet(fleet, cache)]
            found = [t - SWEEP_START_S for t in onsets if t is not None]
            lines.append(f"{axis:<5} {size:5.2f}°: found in {len(found)} of {seeds} logs"
                         + (f", onset errors {', '.join(f'{e:+g} s' for e in found)}"
                            if found else ""))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=50, help="logs in the fleet (50)")
    parser.add_argument("--seed", type=int, default=0, help="the fleet's plan (0)")
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                        help=f"recordings are kept and reused here (default {DEFAULT_CACHE})")
    parser.add_argument("--sweep", type=int, metavar="SEEDS",
                        help="instead: the smallest drift found per axis, over SEEDS logs each")
    args = parser.parse_args()
    if args.sweep:
        print("\n".join(sweep(args.cache, args.sweep)))
        return
    fleet = plan_fleet(args.logs, drifted=max(1, args.logs // 10), seed=args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        found, same, wall = run_fleet(fleet, args.cache, Path(tmp))
    rows, failures = judge(fleet, found)
    print("\n".join(rows))
    drifts = [(log, got) for log, got in zip(fleet, found, strict=True) if log.drift]
    errors = [got.onset_s - log.drift.start_s for log, got in drifts
              if log.drift is not None and got.onset_s is not None]
    clean_flagged = sum(log.drift is None and got.onset_s is not None
                        for log, got in zip(fleet, found, strict=True))
    print(f"{len(fleet)} logs ({SCENARIO} {WIDTH}x{HEIGHT}, {DURATION_S:g} s at "
          f"{RATE_HZ:g} Hz, {WINDOW_S:g} s windows): {len(drifts)} drifted, "
          f"{sum(g.onset_s is not None for _, g in drifts)} found; clean logs flagged: "
          f"{clean_flagged}; onset errors: "
          + (", ".join(f"{e:+.2f} s" for e in errors) or "none"))
    print(f"process engine {wall['process']:.1f} s, Ray {wall['ray']:.1f} s (with its "
          f"start-up); check.csv of every log identical on both: {'yes' if same else 'NO'}")
    found_share = sum(g.onset_s is not None for _, g in drifts) / max(1, len(drifts))
    emit(f"check: fleet of {len(fleet)} logs, drifts found", baseline="drifted logs",
         baseline_value=len(drifts), measured="found", measured_value=found_share * len(drifts),
         unit="logs", ratio=found_share, target="every pitch and roll drift")
    if not same:
        failures.append("the process and Ray engines' check.csv differ")
    for failure in failures:
        print(f"FAILED: {failure}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
