"""The quick-start demo: record → resync → calibrate → process → view, on built-ins.

1. record ``stereo_unsynced`` (two independently stamped cameras over a moving board),
   resync the unsynchronised pair and calibrate it (intrinsics, baseline, rectification);
2. meanwhile, in a second process, record ``red_block`` (the rig over a red block) and run
   red pixels and Canny edges on its left camera;
3. view everything in one rerun recording (in a fresh process, so that the largest process
   holds what one step needs, not the sum of the steps).

The two chains share nothing until the view, so they run concurrently. Every output goes
under one folder, which the demo owns: re-running replaces its files.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from processors.registry import configure
from recorder.record import record
from recorder.scenario import load_scenario
from rerun_export import view_logs

from .calibrate.flow import calibrate_log
from .lean import pandas_hidden, without_pandas
from .processing.process_log import process_log
from .processing.resync_log import resync_log
from .requests.calibrate import CalibrateRequest
from .requests.demo import DemoRequest
from .requests.processing import ProcessRequest, ResyncRequest


@dataclass
class DemoResult:
    """Where each output went, step by step, and what the steps measured."""

    outputs: list[tuple[str, Path, str]] = field(default_factory=list)
    wall_s: float = 0.0


def size_of(path: Path) -> str:
    """``12.3 MB``: a file's size, or the total of a folder's files."""
    files = [path] if path.is_file() else [p for p in path.rglob("*") if p.is_file()]
    return f"{sum(p.stat().st_size for p in files) / 1e6:.1f} MB"


def red_block_chain(out_dir: Path, seed: int) -> list[tuple[str, Path, str]]:
    """Record red_block and run red pixels + edges on its left camera (run in a second
    process while the stereo chain runs); returns the steps' (step, path, note)."""
    red = out_dir / "red_block.mcap"
    rec = record(load_scenario("red_block", {"seed": seed}), red, overwrite=True,
                 progress=False)
    processed = out_dir / "red_block_processed.mcap"
    proc = process_log(ProcessRequest(
        log=red, output=processed, topic=("/stereo_camera/left/image_raw",),
        processors=(configure("red_pixels"), configure("edges")), overwrite=True,
        progress=False))
    return [("record", red, f"{sum(rec.frames.values())} frames, {rec.wall_s:.1f} s"),
            ("process", processed, f"red pixels + edges on {proc.frames_processed} frames, "
                                   f"{proc.wall_s:.1f} s")]


def view_chain(logs: list[Path], rrd: Path, progress: bool | None, *,
               hide_pandas: bool) -> int:
    """View the demo's logs into ``rrd``; returns the number of recordings. Run in a fresh
    process: what the stereo chain's process holds by then (MuJoCo, the calibration's
    buffers kept for reuse) would otherwise add to the view's own memory."""
    if hide_pandas:  # as the camlog program that started the demo does
        without_pandas()
    return view_logs(logs, output=rrd, overwrite=True, progress=progress).recordings


def _stereo_chain(out_dir: Path, duration_s: float, seed: int, progress: bool | None,
                  done: Callable[[str, Path, str], None]) -> Path:
    """Record stereo_unsynced, resync and calibrate it; returns the calibration folder."""
    unsynced = out_dir / "stereo_unsynced.mcap"
    rec = record(load_scenario("stereo_unsynced", {"duration_s": duration_s, "seed": seed}),
                 unsynced, overwrite=True, progress=progress)
    drops = sum(len(d) for d in rec.dropped.values())
    done("record", unsynced, f"{sum(rec.frames.values())} frames, {drops} dropped, "
         f"{rec.wall_s:.1f} s")

    synced = out_dir / "stereo_synced.mcap"
    sync = resync_log(ResyncRequest(log=unsynced, output=synced, overwrite=True,
                                    progress=progress))
    done("resync", synced, f"{sync.stats.pairs} pairs re-stamped")

    calibration = out_dir / "calibration"
    cal = calibrate_log(CalibrateRequest(
        log=synced, size="7x6", square=0.01, left="/stereo_sync/left",
        right="/stereo_sync/right", output=calibration, overwrite=True, progress=progress))
    stereo = cal.summary.stereo
    assert stereo is not None
    fx = cal.summary.cameras[0].parameters["fx"]
    truth = f" (true {fx.truth:.2f})" if fx.truth is not None else ""
    done("calibrate", calibration,
         f"fx {fx.value:.2f} ± {fx.std:.2f} px{truth}, baseline "
         f"{stereo.baseline_m * 1000:.3f} mm, epipolar RMS {stereo.epipolar_rms_px:.3f} px; "
         "see report.md")
    return calibration


def run_demo(request: DemoRequest, *, say: Callable[[str], None] = print) -> DemoResult:
    """Run the whole demo into the request's ``output`` folder; ``say`` reports each step as
    it finishes."""
    out_dir, duration_s, seed, progress = (request.output, request.duration, request.seed,
                                           request.progress)
    started = time.perf_counter()
    out_dir.mkdir(parents=True, exist_ok=True)
    result = DemoResult()

    def done(step: str, path: Path, note: str) -> None:
        result.outputs.append((step, path, note))
        say(f"{step:10} {path}  {size_of(path)}  ({note})")

    # the red-block chain in a fresh process (spawn: no inherited GL or thread state)
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        red_chain = pool.submit(red_block_chain, out_dir, seed)
        calibration = _stereo_chain(out_dir, duration_s, seed, progress, done)
        red_steps = red_chain.result()
    for step, path, note in red_steps:
        done(step, path, note)
    processed = red_steps[-1][1]

    rrd = out_dir / "demo.rrd"
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        recordings = pool.submit(view_chain, [calibration / "calibration.mcap", processed],
                                 rrd, progress, hide_pandas=pandas_hidden()).result()
    # the stereo calibration and the red block are unrelated: a recording each
    done("view", rrd, f"{recordings} recordings; open with: rerun {rrd}")
    result.wall_s = time.perf_counter() - started
    return result
