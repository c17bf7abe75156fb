"""``camlog golden``'s request: check, update or re-record the golden logs, which of them,
and where inputs, expected outputs and differences are."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from .fields import option, required
from .values import bounded_int

__all__ = ["GOLDEN_ACTIONS", "GoldenRequest"]

#: compare with, regenerate, or re-record the goldens
GOLDEN_ACTIONS = ("check", "update", "record")


@dataclass(frozen=True, kw_only=True)
class GoldenRequest:
    """Golden-log regression: check, update or re-record the committed golden logs."""

    epilog: ClassVar[str] = (
        "check: verify the inputs' sha256 against manifest.json, run every job (calibrate, "
        "resync, process) over them and compare with the expected outputs (exit 1 on a "
        "difference; image failures write expected/actual/difference PNGs to --diff-dir). "
        "update: rewrite the expected outputs that changed and print what changed. "
        "record: re-render the inputs and rewrite manifest.json (rendering depends on the GL "
        "stack: commit new inputs together with `camlog golden update`)."
    )

    action: str = required(choices=GOLDEN_ACTIONS, batch=False,
                           help="compare with, regenerate, or re-record the goldens")
    only: tuple[str, ...] = option((), "--only", action="append", metavar="INPUT",
                                   help="one golden input, by file stem or scenario "
                                        "(repeatable)")
    inputs: Path | None = option(None, "--inputs", type=Path, metavar="DIR",
                                 help="golden inputs and manifest.json (default "
                                      "datasets/golden)")
    expected: Path | None = option(None, "--expected", type=Path, metavar="DIR",
                                   help="expected outputs (default: INPUTS/expected)")
    diff_dir: Path = option(Path("golden_diff"), "--diff-dir", type=Path, metavar="DIR",
                            help="where check writes images that differ (default "
                                 "./golden_diff)")
    work_dir: Path | None = option(None, "--work-dir", type=Path, metavar="DIR",
                                   help="keep the jobs' output logs here (default: a "
                                        "temporary folder)")
    workers: int = option(1, "--workers", type=bounded_int(1, 64), metavar="N",
                          help="threads per job (outputs must not depend on it; default 1)")
