"""The docs run and hold together: every ``sh`` block of README.md and of the pages of
``docs/`` runs, in reading order (the README, then the pages as ``docs/README.md`` lists
them), in one temporary folder, and what each command says it writes (``-o OUT``,
``convert IN OUT``) exists afterwards; every page is reachable from the README, and every
relative link and picture resolves.

A block the suite cannot run says why in a ``<!-- docs-test: skip (reason) -->`` line right
above it. Recordings are made shorter (the 30 s calibration recordings also 320x240: they
feed every later block, which shows the same at a quarter of the pixels), and a viewer is
replaced by an .rrd file, through SMALLER: each entry must still occur in a runnable block,
so a stale entry fails instead of silently testing nothing.
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

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
INDEX = DOCS / "README.md"
CONTRIBUTING = ROOT / "CONTRIBUTING.md"
SKIP = re.compile(r"<!-- docs-test: skip \((?P<reason>[^)]+)\) -->")
#: docs text -> what the suite runs instead (shorter logs; files instead of a viewer)
SMALLER = {
    "--duration 4 --resolution 320x240": "--duration 2 --resolution 320x240",
    "--duration 30": "--duration 4 --resolution 320x240",
    "--duration 10": "--duration 0.1",
    "--duration 2": "--duration 0.5",
    "--start 10 --end 20": "--start 1 --end 3",
    "--spawn": "-o spawned.rrd",
    "--connect 127.0.0.1:9876": "-o connected.rrd",
}
#: the longest line of prose (outside code blocks and tables) in the docs
MAX_LINE = 120
#: a Markdown link or picture: [text](target) or ![alt](target "title")
LINK = re.compile(r"!?\[[^\]]*\]\((?P<target>[^)\s]+)(?:\s+\"[^\"]*\")?\)")


@dataclass(frozen=True)
class Block:
    """One fenced ``sh`` block: its page, first line number, commands, why it is skipped."""

    page: str
    line: int
    commands: tuple[str, ...]
    skip: str | None


def reading_order() -> list[Path]:
    """README.md, then the pages of ``docs/`` in the order ``docs/README.md`` links them."""
    listed = [DOCS / target for target in link_targets(INDEX.read_text())
              if "/" not in target and target.endswith(".md")]
    return [README, INDEX, *dict.fromkeys(listed)]


def link_targets(text: str) -> list[str]:
    """The targets of the links and pictures of Markdown ``text``, code left out."""
    return [m["target"] for m in LINK.finditer(_prose(text))]


def _prose(text: str) -> str:
    """``text`` without fenced blocks and inline code (links there are not links)."""
    text = re.sub(r"^ *```.*?^ *```", "", text, flags=re.M | re.S)
    return re.sub(r"`[^`]*`", "", text)


def shell_blocks(text: str, page: str) -> list[Block]:
    """The ``sh`` blocks of one page in order (commands without comments or blank lines)."""
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
        blocks.append(Block(page, start + 1, tuple(commands),
                            marker["reason"] if marker else None))
    return blocks


def smaller(command: str) -> str:
    """The command as the suite runs it (SMALLER applied in one pass, the longest entry first
    where two start at one place, so that no replacement is replaced again; whole words:
    ``--duration 2`` leaves ``--duration 20`` alone)."""
    entries = "|".join(map(re.escape, sorted(SMALLER, key=len, reverse=True)))
    return re.sub(rf"(?:{entries})(?![\w.])", lambda m: SMALLER[m[0]], command)


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


def slug(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation dropped, spaces to
    hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(text: str) -> set[str]:
    """Every heading anchor of a page (a repeated heading gets ``-1``, ``-2``…)."""
    found: set[str] = set()
    for match in re.finditer(r"^#{1,6} +(.+?) *$", re.sub(r"^ *```.*?^ *```", "", text,
                                                             flags=re.M | re.S), flags=re.M):
        base = slug(match[1])
        name, n = base, 0
        while name in found:
            n += 1
            name = f"{base}-{n}"
        found.add(name)
    return found


PAGES = reading_order()
BLOCKS = [block for page in PAGES
          for block in shell_blocks(page.read_text(), str(page.relative_to(ROOT)))]
MARKDOWN = [README, CONTRIBUTING, *sorted(DOCS.glob("*.md"))]


def test_every_page_is_in_the_reading_order_and_reachable_from_the_readme() -> None:
    pages = set(DOCS.glob("*.md"))
    assert pages - set(PAGES) == set(), "docs/README.md must list every page"
    linked = {(README.parent / target.split("#")[0]).resolve()
              for target in link_targets(README.read_text())}
    assert INDEX.resolve() in linked, "README.md must link docs/README.md"
    assert CONTRIBUTING.resolve() in linked, "README.md must link CONTRIBUTING.md"


@pytest.mark.parametrize("page", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_and_picture_resolves(page: Path) -> None:
    broken = [target for target in link_targets(page.read_text())
              if not re.match(r"[a-z]+:", target) and leads_nowhere(page, target)]
    assert not broken, f"{page.relative_to(ROOT)}: links that lead nowhere: {broken}"


def leads_nowhere(page: Path, target: str) -> bool:
    """Whether a relative link of ``page`` names a missing file, or a heading its page lacks."""
    path, _, anchor = target.partition("#")
    where = (page.parent / path).resolve() if path else page
    if not where.exists():
        return True
    return bool(anchor) and where.suffix == ".md" and anchor not in anchors(where.read_text())


@pytest.mark.parametrize("page", MARKDOWN, ids=lambda p: str(p.relative_to(ROOT)))
def test_prose_lines_are_short(page: Path) -> None:
    long = [number for number, line in _lines_of_prose(page.read_text())
            if len(line) > MAX_LINE]
    assert not long, f"{page.relative_to(ROOT)}: lines over {MAX_LINE} characters: {long}"


def _lines_of_prose(text: str) -> list[tuple[int, str]]:
    """(number, line) of the lines outside fenced blocks and tables."""
    found, fenced = [], False
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced and not line.lstrip().startswith("|"):
            found.append((number, line))
    return found


def test_the_docs_have_runnable_blocks_and_every_substitution_is_used() -> None:
    runnable = [block for block in BLOCKS if block.skip is None]
    assert len(runnable) >= 4
    text = "\n".join(command for block in runnable for command in block.commands)
    stale = [docs for docs in SMALLER if docs not in text]
    assert not stale, f"SMALLER entries no longer in the docs' runnable blocks: {stale}"


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The one folder every block runs in, in order (later blocks read earlier outputs)."""
    return tmp_path_factory.mktemp("docs")


@pytest.mark.slow
@pytest.mark.parametrize("block", [b for b in BLOCKS if b.skip is None],
                         ids=lambda b: f"{b.page}:{b.line}")
def test_block_runs_and_writes_its_outputs(block: Block, folder: Path) -> None:
    env = dict(os.environ)
    # the camlog (and rerun) of the interpreter running the suite
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    for command in map(smaller, block.commands):
        done = subprocess.run(["bash", "-c", command], cwd=folder, env=env, text=True,
                              capture_output=True, timeout=600, check=False)
        assert done.returncode == 0, (f"{block.page} line {block.line}: {command}\n"
                                      f"{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
        for output in outputs_of(command):
            assert (folder / output).exists(), f"{command}: no {output}"


def test_skipped_blocks_say_why() -> None:
    skipped = [block for block in BLOCKS if block.skip is not None]
    assert all(len(block.skip or "") > 20 for block in skipped)
    # what a new user runs first stays in the README, even though the suite cannot run it
    assert any("camlog demo" in " ".join(block.commands) for block in skipped
               if block.page == "README.md")
