"""The command-line reference (``docs/cli.md``), generated from camlog's argument parser.

Every command's usage, description, notes and options with their help, as ``camlog COMMAND
--help`` prints them, in Markdown. The parser is built from the commands' requests, so the
page follows their declarations::

    python -m camlog.cli.reference > docs/cli.md
"""

from __future__ import annotations

import argparse
import re
import sys
import textwrap

from . import COMMANDS, build_parser

__all__ = ["reference"]

#: width of the usage blocks and of the page's lines
WIDTH = 96
PAGE = "docs/cli.md"
REGENERATE = f"python -m camlog.cli.reference > {PAGE}"


class _Formatter(argparse.HelpFormatter):
    """argparse's own wording of an option's flags and help, at a fixed width."""

    def __init__(self, prog: str) -> None:
        super().__init__(prog, width=WIDTH, max_help_position=32)

    def invocation(self, action: argparse.Action) -> str:
        """``-o OUT, --output OUT`` as ``--help`` shows it."""
        return self._format_action_invocation(action)

    def expanded_help(self, action: argparse.Action) -> str:
        """The help with ``%(default)s`` and the like filled in, on one line."""
        return " ".join(self._expand_help(action).split()) if action.help else ""


def _markdown(text: str) -> str:
    """Plain help text safe in Markdown prose (no emphasis, tags or code spans by accident)."""
    return re.sub(r"([\\`*_<>\[\]])", r"\\\1", text)


def _paragraph(text: str, *, indent: str = "", first: str = "") -> list[str]:
    return textwrap.wrap(text, width=WIDTH, initial_indent=first or indent,
                         subsequent_indent=indent, break_on_hyphens=False,
                         break_long_words=False)


def _command(name: str, parser: argparse.ArgumentParser) -> list[str]:
    parser.formatter_class = _Formatter
    formatter = _Formatter(parser.prog)
    # argparse indents the usage's later lines under the program's name after "usage: "
    usage = textwrap.dedent(" " * len("usage: ") + parser.format_usage()[len("usage: "):])
    usage = usage.rstrip()
    lines = [f"## camlog {name}", "", *_paragraph(_markdown(parser.description or "")), "",
             "```text", usage, "```", ""]
    if parser.epilog:
        lines += [*_paragraph(_markdown(" ".join(parser.epilog.split()))), ""]
    for action in parser._actions:
        if "--help" in action.option_strings:
            continue
        flags = ", ".join(f"`{part}`" for part in formatter.invocation(action).split(", "))
        help_text = _markdown(formatter.expanded_help(action))
        lines += _paragraph(f"{flags}: {help_text}" if help_text else flags,
                            first="- ", indent="  ")
    return [*lines, ""]


def reference() -> str:
    """The Markdown of ``docs/cli.md``: every command, its usage and its options."""
    parser = build_parser()
    commands: dict[str, argparse.ArgumentParser] = next(
        action.choices for action in parser._actions if isinstance(action.choices, dict))
    index = ", ".join(f"[{name}](#camlog-{name})" for name in COMMANDS)
    lines = ["# Command-line reference", "",
             *_paragraph(f"Every `camlog` command with its options, as `camlog COMMAND --help` "
                         f"prints them. This page is generated from the commands' "
                         f"declarations (`{REGENERATE}`); the test suite checks that it is "
                         f"current."),
             "", *_paragraph(f"Commands: {index}."), ""]
    for name in COMMANDS:
        lines += _command(name, commands[name])
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    sys.stdout.write(reference())
