"""The command-line reference page is what the parser says today."""

from __future__ import annotations

from pathlib import Path

from camlog.cli import COMMANDS
from camlog.cli.reference import PAGE, REGENERATE, reference

ROOT = Path(__file__).resolve().parents[3]


def test_the_committed_reference_is_current() -> None:
    committed = (ROOT / PAGE).read_text()
    assert committed == reference(), f"{PAGE} is out of date: run {REGENERATE}"


def test_every_command_and_option_is_in_the_reference() -> None:
    from camlog.cli import build_parser

    page = reference()
    parser = build_parser()
    commands = next(a.choices for a in parser._actions
                    if isinstance(getattr(a, "choices", None), dict))
    for name in COMMANDS:
        assert f"\n## camlog {name}\n" in page
        options = [flag for action in commands[name]._actions
                   for flag in action.option_strings if flag not in ("-h", "--help")]
        section = page.split(f"\n## camlog {name}\n")[1].split("\n## ")[0]
        missing = [flag for flag in options if f"`{flag}" not in section]
        assert not missing, f"camlog {name}: {missing} not in the reference"
