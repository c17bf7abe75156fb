"""Fuzzing: about two thousand seeded mutants of small valid logs (see tests/replay/fuzz.py).

Every mutant either reads or ends in one camlog error line — never another exception, never
a hang, never an allocation the damage asks for. A few of them go through the real CLI too.
"""

from __future__ import annotations

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

from replay import open_reader
from replay.errors import ReplayError

from .fuzz import SEEDS, Tally, make_mutant, write_seed

#: mutants per format, about 6 s of reading each on one core (a case of a single-file log
#: takes ~8 ms; the rosbag2 formats parse a metadata.yaml per case, 30-60 ms). The mutants
#: come from a seeded generator, so a shorter run reads the first cases of a longer one:
#: run ``python -m tests.replay.fuzz`` with more cases to search further
CASES = {"mcap": 800, "rosbag2 (mcap)": 200, "rosbag2 (sqlite3)": 150, "ros1": 800}
#: a case that takes longer hangs (each takes milliseconds)
TIME_BOUND_S = 10.0
#: a case may raise the peak virtual memory by at most this (the seeds are a few kB; damage
#: asks for up to 2**64 B)
MEMORY_BOUND_BYTES = 64 * 1024 * 1024
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The valid log of each fuzzed format."""
    folder = tmp_path_factory.mktemp("seeds")
    paths = {}
    for index, name in enumerate(SEEDS):
        (folder / str(index)).mkdir()
        paths[name] = write_seed(name, folder / str(index))
    return paths


def test_seeds_are_valid_logs(seeds: dict[str, Path]) -> None:
    for path in seeds.values():
        with open_reader(path) as reader:
            assert reader.warnings == []
            assert reader.message_count == 14
            assert len(list(reader.frames())) == 12


#: run in a fresh process by the next test: a case that asks for 2 GiB (of which no page is
#: touched, as a damaged length did), one that sleeps past its bound, one that raises
BOUNDS_CHECK = """
import dataclasses, json, time
import numpy as np
from tests.replay.fuzz import Tally, run_case
tally = Tally()
for label, case, bound_s in [
        ("nothing", lambda: None, 1.0),
        ("2 GiB", lambda: np.empty(1 << 31, np.uint8).shape and None, 1.0),
        ("sleep", lambda: time.sleep(5), 0.2),
        ("key", lambda: {}["key"], 1.0)]:
    run_case(case, tally, label, time_s=bound_s, memory_bytes=%d)
print(json.dumps(dataclasses.asdict(tally)))
"""


@pytest.mark.slow
def test_the_bounds_catch_what_they_bound() -> None:
    result = subprocess.run([sys.executable, "-c", BOUNDS_CHECK % MEMORY_BOUND_BYTES],
                            cwd=ROOT, capture_output=True, text=True, timeout=120, check=True)
    tally = Tally(**json.loads(result.stdout.splitlines()[-1]))
    assert tally.cases == 4
    assert tally.read == 2  # the 2 GiB case completes, and fails its bound
    assert [f.split(":")[0] for f in tally.failures] == ["2 GiB", "sleep", "key"]


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SEEDS))
def test_damaged_logs_read_or_fail_in_one_line(name: str, tmp_path: Path) -> None:
    # a fresh process: its peak virtual memory is the fuzzed reads' alone. One malloc arena:
    # glibc reserves 64 MiB of address space for each thread's own arena the first time that
    # thread allocates (the MCAP reader reads chunks ahead on a thread), which is address
    # space, not memory a damaged length made the reader allocate
    result = subprocess.run(
        [sys.executable, "-m", "tests.replay.fuzz", name, str(CASES[name]),
         str(list(SEEDS).index(name)), str(tmp_path), str(TIME_BOUND_S),
         str(MEMORY_BOUND_BYTES)],
        cwd=ROOT, capture_output=True, text=True, timeout=600, check=False,
        env={**os.environ, "MALLOC_ARENA_MAX": "1"})
    assert result.returncode == 0, result.stderr[-3000:]
    tally = Tally(**json.loads(result.stdout.splitlines()[-1]))
    print(f"\nfuzz {name}: {tally.cases} cases, {tally.read} read to the end, {tally.errors} "
          f"one-line camlog errors, {len(tally.failures)} failures (tracebacks, hangs, "
          f"memory); peak virtual memory raised by at most {tally.peak_bytes / 1e6:.1f} MB")
    assert not tally.failures, "\n".join(tally.failures)
    assert tally.cases == CASES[name]
    # the damage reached both ends: logs that still read, and logs refused in one line
    assert tally.read > CASES[name] // 10
    assert tally.errors > CASES[name] // 20


def _opens(path: Path) -> bool:
    try:
        with open_reader(path):
            return True
    except ReplayError:
        return False


def _cli_picks(seed_path: Path, folder: Path, seed: int) -> list[tuple[Path, str, bool]]:
    """Two mutants that camlog refuses to open and one it opens: ``(path, what, opens)``."""
    rng = random.Random(seed)
    picks: list[tuple[Path, str, bool]] = []
    for index in range(500):
        target = folder / f"case{index}" / seed_path.name
        target.parent.mkdir()
        what = make_mutant(seed_path, target, rng)
        opens = _opens(target)
        if sum(1 for *_, o in picks if o == opens) < (1 if opens else 2):
            picks.append((target, what, opens))
        if len(picks) == 3:
            return picks
    raise AssertionError(f"no three mutants of {seed_path} to try through the CLI")


def _camlog(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "camlog", *map(str, args)],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "MUJOCO_GL": "egl"}, check=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SEEDS))
def test_damaged_logs_through_the_cli(name: str, seeds: dict[str, Path], tmp_path: Path) -> None:
    """info and convert on mutants: exit 0 with an output that opens, or exit 1 with one
    error line and nothing written; a log that does not open always exits 1."""
    for path, what, opens in _cli_picks(seeds[name], tmp_path, seed=100 + len(name)):
        out = path.parent / "out.mcap"
        for command in (("info", path), ("convert", path, out)):
            result = _camlog(*command)
            where = f"camlog {command[0]} on {name} {what}: {result.stderr}"
            assert "Traceback" not in result.stderr, where
            assert result.returncode in ((0, 1) if opens else (1,)), where
            if result.returncode == 1:
                errors = [line for line in result.stderr.splitlines() if "error" in line]
                assert len(errors) == 1, where
                assert errors[0].startswith(f"camlog {command[0]}: error: "), where
                assert errors[0] == result.stderr.splitlines()[-1], where
                assert sorted(p.name for p in path.parent.iterdir()) == [path.name], where
            elif command[0] == "convert":
                with open_reader(out) as reader:
                    assert reader.message_count > 0, where
