"""Whether the stated projection uncertainty tells the truth, everywhere in the image.

For every scenario over many seeds, camlog calibrates with the flags a user gives (its default
lens order; ``--model`` where the lens needs it) and its stated uncertainty for rays (1 sigma
in the worst direction, what the only model's leaves out included, the ``rays`` figures of the
terminal and ``calibration.json``) is set against the real error at the same grid of image
points: the distance between where the calibrated and the true camera image each pixel's ray,
the camera frames aligned by the best rotation (as the max projection difference). Grid pixels
16 px apart inside a 16 px margin (a fisheye within 80° of its axis); a pair's two cameras
both count. Per scenario: the share of points whose real error is within 1, 3 and 5 sigma
(pooled over the seeds; a normal law puts 39 %, 99 % and 100 % of 2-D errors there), the same
share within 3 sigma where no board reached (:mod:`processors.calibration.beyond`), and the
worst ratio of real error to stated sigma over every point of every seed.

Scenarios: ``vs_mrcal``'s recordings (``mono_heldout``, ``stereo_heldout``, ``mono_charuco``
with ``--model rational_polynomial``, ``mono_moving_blur`` through its own lens and through a
k3 lens, ``mono_fisheye`` with ``--model fisheye``; kept in its cache) and the analytic moving
board through a k3 lens with tangential terms (``vs_script``'s ``moving_k3``, 10 s). Each
seed's figures are appended to ``--keep FILE`` (JSON lines) and read back by a later run.

    python -m benchmarks.calibration_honesty [--cases heldout,...] [--seeds 20] [--keep FILE]
        [--write-docs]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from camlog.errors import CalibrationError
from processors.calibration.beyond import reached
from processors.calibration.validation import projection_difference

from . import vs_mrcal, vs_script
from .calibrate_speed import Case, calibrate
from .calibration_truth import FISHEYE_AXIS_DEG, MARGIN_PX
from .docs import add_write_docs, markdown_table, write_table

#: scenario -> the case that records it
CASES: dict[str, Case | vs_script.ScriptCase] = {
    **{c.name: c for c in vs_mrcal.CASES},
    "moving_k3": vs_script.CASES[0],
}
CASE_NAMES = list(CASES)
DEFAULT_KEEP = Path.home() / ".cache" / "camlog" / "calibration_honesty.jsonl"
SCRIPT_SECONDS = 10.0


@dataclass
class SeedFigures:
    """One seed of one scenario: ratios real error / stated sigma at the grid points, and
    which of them lie beyond the boards."""

    case: str
    seed: int
    ratios: list[float]
    beyond: list[bool]


def _path_and_flags(name: str, seed: int) -> tuple[Path, str]:
    case = CASES[name]
    if isinstance(case, vs_script.ScriptCase):
        return vs_script.recording(case, seed, SCRIPT_SECONDS, vs_script.DEFAULT_CACHE), \
            case.flags
    return vs_mrcal.recording(case, seed, vs_mrcal.DEFAULT_CACHE, None), \
        vs_mrcal.default_flags(case.flags)


def one_seed(name: str, seed: int, tmp: Path) -> SeedFigures:
    """Calibrate one seed and set the stated sigma against the real error."""
    path, flags = _path_and_flags(name, seed)
    run = calibrate(path, flags, tmp / "out", report=False)
    ratios: list[float] = []
    beyond: list[bool] = []
    for camera, stats in zip(run.solved.cameras, run.statistics, strict=True):
        assert camera.truth is not None, "the log has no ground truth"
        truth = camera.truth.model()
        umap = stats.rays_uncertainty
        pixels = umap.pixels.reshape(-1, 2)
        width, height = camera.views.size
        keep = ((pixels[:, 0] >= MARGIN_PX) & (pixels[:, 0] <= width - 1 - MARGIN_PX)
                & (pixels[:, 1] >= MARGIN_PX) & (pixels[:, 1] <= height - 1 - MARGIN_PX))
        if truth.is_fisheye:
            rays = truth.pixel_rays(pixels)
            cos = rays[:, 2] / np.linalg.norm(rays, axis=1)
            keep &= np.isfinite(cos) & (np.degrees(np.arccos(np.clip(cos, -1, 1)))
                                        <= FISHEYE_AXIS_DEG)
        real = projection_difference(camera.model, truth, pixels[keep])
        sigma = umap.sigma_px.reshape(-1)[keep]
        mask = reached(camera.views.size, run.solved.used_corners(camera))
        u = np.clip(np.round(pixels[keep, 0]).astype(int), 0, width - 1)
        v = np.clip(np.round(pixels[keep, 1]).astype(int), 0, height - 1)
        finite = np.isfinite(real) & np.isfinite(sigma) & (sigma > 0)
        ratios += (real[finite] / sigma[finite]).tolist()
        beyond += (~mask[v, u])[finite].tolist()
    return SeedFigures(name, seed, ratios, beyond)


def _share(ratios: np.ndarray, within: float) -> str:
    return f"{100 * float(np.mean(ratios <= within)):.1f} %" if len(ratios) else ""


def table(figures: Sequence[SeedFigures]) -> list[str]:
    """The honesty table, one row per scenario."""
    rows = []
    for name in CASE_NAMES:
        mine = [f for f in figures if f.case == name]
        if not mine:
            continue
        ratios = np.concatenate([np.asarray(f.ratios) for f in mine])
        beyond = np.concatenate([np.asarray(f.beyond, dtype=bool) for f in mine])
        worst = [max(f.ratios) for f in mine if f.ratios]
        rows.append([f"`{name}`", str(len(mine)), str(len(ratios)), _share(ratios, 1.0),
                     _share(ratios, 3.0), _share(ratios, 5.0), _share(ratios[beyond], 3.0),
                     f"{statistics.median(worst):.2f}", f"{max(worst):.2f}"])
    return markdown_table(["scenario", "seeds", "points", "≤ 1σ", "≤ 3σ", "≤ 5σ",
                           "≤ 3σ beyond the boards", "worst real/σ: median", "worst"], rows)


def _kept(keep: Path) -> dict[tuple[str, int], SeedFigures]:
    if not keep.exists():
        return {}
    out = {}
    for line in keep.read_text().splitlines():
        if line.strip():
            f = SeedFigures(**json.loads(line))
            out[(f.case, f.seed)] = f
    return out


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default=",".join(CASE_NAMES),
                        help=f"comma-separated, from {', '.join(CASE_NAMES)}")
    parser.add_argument("--seeds", type=int, default=20, help="seeds per case (default 20)")
    parser.add_argument("--keep", type=Path, default=DEFAULT_KEEP,
                        help=f"each seed's figures are kept and reused (default {DEFAULT_KEEP})")
    add_write_docs(parser)
    args = parser.parse_args(argv)
    names = args.cases.split(",")
    unknown = sorted(set(names) - set(CASE_NAMES))
    if unknown:
        parser.error(f"unknown cases {', '.join(unknown)} (known: {', '.join(CASE_NAMES)})")
    kept = _kept(args.keep)
    figures = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.seeds):
            for name in names:
                if (name, seed) not in kept:
                    try:
                        kept[(name, seed)] = one_seed(name, seed, Path(tmp))
                    except CalibrationError as err:
                        print(f"{name} seed {seed}: calibration failed: {err}", flush=True)
                        continue
                    args.keep.parent.mkdir(parents=True, exist_ok=True)
                    with args.keep.open("a") as out:
                        out.write(json.dumps(asdict(kept[(name, seed)])) + "\n")
                f = kept[(name, seed)]
                figures.append(f)
                ratios = np.asarray(f.ratios)
                print(f"{name} seed {seed}: {len(ratios)} points, within 3σ "
                      f"{_share(ratios, 3.0)}, worst real / σ {ratios.max():.2f}", flush=True)
    lines = table(figures)
    print("\n".join(lines))
    if args.write_docs:
        write_table("calibration_honesty", lines)


if __name__ == "__main__":
    main()
