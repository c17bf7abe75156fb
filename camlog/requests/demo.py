"""``camlog demo``'s request: where the outputs go, how long the stereo recording is, and
the seed of both scenarios."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from . import fields as common
from .fields import option
from .values import positive

__all__ = ["DemoRequest"]


@dataclass(frozen=True, kw_only=True)
class DemoRequest:
    """Run the whole workflow on built-in scenarios: record, resync, calibrate, process,
    view."""

    epilog: ClassVar[str] = (
        "Records stereo_unsynced, resyncs the unsynchronised pair and calibrates it; "
        "meanwhile records red_block and runs red pixels + edges on it; then writes one "
        "rerun recording of the results. Each step prints what it wrote and its size. "
        "Re-running replaces the folder's files."
    )

    output: Path = option(Path("demo"), "-o", "--output", type=Path, metavar="OUTDIR",
                          batch=False, help="folder for every output (default ./demo)")
    duration: float = option(8.0, "--duration", type=positive, metavar="S",
                             help="length of the stereo recording in seconds (default 8)")
    seed: int = option(0, "--seed", type=int, help="random seed of both scenarios")
    progress: bool | None = common.progress()
