"""The board warp on the real corpus: where cross-validation chooses it, its size, and the RMS
and held-out error with the board flat and warped.

Each fetched dataset is calibrated as :mod:`.run` does (the manifest's board and model),
once with ``--board-warp auto`` (camlog's default: the choice and its held-out errors) and
once with ``--board-warp on`` (the warp's size with its standard deviation, and the RMS with
it); the flat RMS is the auto run's when it held the board flat.

    python -m benchmarks.corpus.warp [--cache DIR] [--only NAME…]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from .manifest import CorpusError, Dataset, default_cache, load_manifest
from .run import camlog_calibration

HEADER = ("| dataset | auto: held-out RMS px flat / warped, gain, p | chosen | warp mm (x, y) "
          "± std | RMS px flat / warped |")


def _summary(dataset: Dataset, folder: Path, work: Path, mode: str) -> dict[str, Any]:
    camlog_calibration(dataset, folder, work, extra=("--board-warp", mode))
    out: dict[str, Any] = json.loads(
        (work / f"{dataset.name}_calibration" / "calibration.json").read_text())
    return out


def _rms(summary: dict[str, Any]) -> str:
    return "+".join(f"{c['rms_px']:.4f}" for c in summary["cameras"])


def warp_row(dataset: Dataset, folder: Path, work: Path) -> str:
    """One table row: the auto choice, the warp estimated, the RMS both ways."""
    auto = _summary(dataset, folder, work, "auto")
    on = _summary(dataset, folder, work, "on")
    choice = auto["board_warp"]
    if "held_out_rms_px" in choice:
        flat_px, warped_px = choice["held_out_rms_px"]
        evidence = (f"{flat_px:.4f} / {warped_px:.4f}, {100 * choice['gain']:+.1f} %, "
                    f"p = {choice['p_value']:.2g} ({choice['views']} board poses)")
    else:
        evidence = choice["summary"]
    flat = _rms(_summary(dataset, folder, work, "off")) if choice["estimated"] else _rms(auto)
    warp = on["board_warp"]
    size = ", ".join(f"{w:+.3f} ± {s:.3f}" for w, s in
                     zip(warp["warp_mm"], warp["warp_std_mm"], strict=True))
    return (f"| {dataset.name} | {evidence} | {'yes' if choice['estimated'] else 'no'} | "
            f"{size} | {flat} / {_rms(on)} |")


def main() -> int:
    """Parse the command line, run, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", type=Path, default=default_cache())
    parser.add_argument("--only", nargs="+", metavar="NAME")
    args = parser.parse_args()
    lines = [HEADER, "| " + " | ".join("---" for _ in range(5)) + " |"]
    with tempfile.TemporaryDirectory(prefix="camlog-warp-") as work:
        for dataset in load_manifest():
            folder = args.cache / dataset.name
            if (args.only and dataset.name not in args.only) or not folder.is_dir():
                continue
            try:
                lines.append(warp_row(dataset, folder, Path(work)))
            except (CorpusError, KeyError, OSError) as error:
                lines.append(f"| {dataset.name} | camlog FAILED: {error} ||||")
            print(lines[-1], file=sys.stderr, flush=True)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
