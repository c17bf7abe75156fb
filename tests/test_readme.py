"""The README's shell examples run: every ``sh`` block, in order, in one temporary folder, and
what each command says it writes (``-o OUT``, ``convert IN OUT``) exists afterwards.

A block the suite cannot run says why in a ``<!-- docs-test: skip (reason) -->`` line right
above it. Recordings are made shorter, and a viewer is replaced by an .rrd file, through
SMALLER: each entry must still occur in the README, so a stale entry fails instead of
silently testing nothing.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
SKIP = re.compile(r"<!-- docs-test: skip \((?P<reason>[^)]+)\) -->")
#: README text -> what the suite runs instead (shorter logs; files instead of a viewer)
SMALLER = {
    "--duration 30": "--duration 4",
    "--duration 10": "--duration 0.1",
    "--duration 2": "--duration 0.5",
    "--start 10 --end 20": "--start 1 --end 3",
    "--spawn": "-o spawned.rrd",
    "--connect 127.0.0.1:9876": "-o connected.rrd",
}


@dataclass(frozen=True)
class Block:
    """One fenced ``sh`` block: its first line number, its commands, why it is skipped."""

    line: int
    commands: tuple[str, ...]
    skip: str | None


def shell_blocks(text: str) -> list[Block]:
    """The README's ``sh`` blocks in order (commands without comments or blank lines)."""
    lines = text.splitlines()
    blocks: list[Block] = []
    index = 0
    while index < len(lines):
        if lines[index].strip() != "```sh":
            index += 1
            continue
        start = index
        index += 1
        commands: list[str] = []
        while lines[index].strip() != "```":
            command = lines[index].strip()
            if command and not command.startswith("#"):
                commands.append(command)
            index += 1
        marker = SKIP.search(lines[start - 1]) if start else None
        blocks.append(Block(start + 1, tuple(commands), marker["reason"] if marker else None))
    return blocks


def smaller(command: str) -> str:
    """The command as the suite runs it (SMALLER applied)."""
    for readme, suite in SMALLER.items():
        command = command.replace(readme, suite)
    return command


def outputs_of(command: str) -> list[str]:
    """What a camlog command says it writes: ``-o``/``--output`` values, convert's OUT."""
    words = shlex.split(command, comments=True)
    if words[:1] != ["camlog"]:
        return []
    found = [words[i + 1] for i, word in enumerate(words[:-1]) if word in ("-o", "--output")]
    if words[1:2] == ["convert"]:
        positional = [w for w in words[2:] if not w.startswith("-")]
        found.append(positional[1])
    return found


BLOCKS = shell_blocks(README.read_text())


def test_the_readme_has_runnable_blocks_and_every_substitution_is_used() -> None:
    runnable = [block for block in BLOCKS if block.skip is None]
    assert len(runnable) >= 4
    text = "\n".join(command for block in runnable for command in block.commands)
    stale = [readme for readme in SMALLER if readme not in text]
    assert not stale, f"SMALLER entries no longer in the README's runnable blocks: {stale}"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The one folder every block runs in, in order (later blocks read earlier outputs)."""
    return tmp_path_factory.mktemp("readme")


@pytest.mark.parametrize("block", [b for b in BLOCKS if b.skip is None],
                         ids=lambda b: f"line{b.line}")
def test_block_runs_and_writes_its_outputs(block: Block, folder: Path) -> None:
    env = dict(os.environ)
    # the camlog (and rerun) of the interpreter running the suite
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    for command in map(smaller, block.commands):
        done = subprocess.run(["bash", "-c", command], cwd=folder, env=env, text=True,
                              capture_output=True, timeout=600, check=False)
        assert done.returncode == 0, (f"README line {block.line}: {command}\n"
                                      f"{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
        for output in outputs_of(command):
            assert (folder / output).exists(), f"{command}: no {output}"


def test_skipped_blocks_say_why() -> None:
    skipped = [block for block in BLOCKS if block.skip is not None]
    assert all(len(block.skip or "") > 20 for block in skipped)
    # what a new user runs first stays in the README, even though the suite cannot run it
    assert any("camlog demo" in " ".join(block.commands) for block in skipped)
