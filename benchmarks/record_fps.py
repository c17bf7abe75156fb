"""Recording throughput against a bare MuJoCo render loop of the same scene, in one run.

The baseline renders every frame of the recording (same scene, cameras, render sizes and
pose changes) and does nothing else; the recording renders a held pose once per camera and
warps, noises, serializes, compresses and writes every frame. The ratio of the two loops
(setup excluded from both) says whether the recording keeps up with rendering (target >=
0.9; above 1 where held poses are not rendered again). End-to-end recording fps, setup
included, is printed too.

    python -m benchmarks.record_fps [SCENARIO] [--frames N] [--repeats R]

SCENARIO (default mono_checkerboard) shapes the ideal and distorted rows; the fisheye row
records mono_fisheye (a multi-view render and its warp), the blur row mono_moving_blur (its
baseline renders the same sub-frames).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from recorder.clock import schedule
from recorder.exposure import rendered_shots
from recorder.motion import plan_trajectory
from recorder.multiview import plan_camera_optics
from recorder.record import CLOCK_STREAM, MOTION_STREAM, record, rng_for
from recorder.render import SceneRenderer
from recorder.scenario import ScenarioSpec, load_scenario

from .docs import add_write_docs
from .report import emit, write_summary_rows


def bare_render_fps(scenario: ScenarioSpec) -> float:
    """Frames per second of rendering alone, over the recording's own shots."""
    optics = [plan_camera_optics(c.model, c.supersample) for c in scenario.cameras]
    duration_s = max(n / c.rate_hz + c.phase_s
                     for n, c in zip(scenario.frame_counts, scenario.cameras, strict=True))
    trajectories = [
        plan_trajectory(t, scenario.cameras, duration_s, rng_for(scenario, MOTION_STREAM, i))
        for i, t in enumerate(scenario.targets)
    ]
    shots, _ = schedule(scenario.cameras, scenario.frame_counts,
                        [rng_for(scenario, CLOCK_STREAM, i) for i in range(len(scenario.cameras))])
    renderer = SceneRenderer(scenario, optics)
    try:
        started = time.perf_counter()
        for _ in rendered_shots(renderer, scenario.cameras, scenario.targets, trajectories,
                                shots, every_frame=True):
            pass
        return len(shots) / (time.perf_counter() - started)
    finally:
        renderer.close()


def record_fps(scenario: ScenarioSpec, out_dir: Path) -> tuple[float, float, int]:
    """Loop and end-to-end frames per second of a recording to MCAP, and its size in bytes."""
    path = out_dir / f"{scenario.name}.mcap"
    result = record(scenario, path, overwrite=True, progress=False)
    return result.loop_fps, result.fps, path.stat().st_size


def run(
    scenario_name: str, frames: int, repeats: int, overrides: dict[str, object]
) -> dict[str, float]:
    scenario = load_scenario(scenario_name, {"frames": frames, **overrides})
    bare, rec, end_to_end = [], [], []
    size = 0
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):  # interleave to share any drift in machine load
            bare.append(bare_render_fps(scenario))
            loop, total, size = record_fps(scenario, Path(tmp))
            rec.append(loop)
            end_to_end.append(total)
    return {"bare_fps": max(bare), "record_fps": max(rec), "ratio": max(rec) / max(bare),
            "end_to_end_fps": max(end_to_end), "mb": size / 1e6}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("scenario", nargs="?", default="mono_checkerboard")
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    rows: list[tuple[str, str, dict[str, object]]] = [
        ("ideal camera", args.scenario, {}),
        ("plumb_bob k1=-0.2, supersample 2", args.scenario,
         {"distortion": [-0.2, 0.05, 0.0, 0.0, 0.0]}),
        ("fisheye 176 deg, multi-view warp", "mono_fisheye", {}),
        ("moving board, 8 ms exposure (blur)", "mono_moving_blur", {}),
    ]
    print(f"{'scenario':18} {'case':34} {'bare fps':>9} {'record fps':>11} {'ratio':>6} "
          f"{'end-to-end':>11} {'MB':>6}")
    for label, scenario, overrides in rows:
        r = run(scenario, args.frames, args.repeats, overrides)
        print(f"{scenario:18} {label:34} {r['bare_fps']:9.1f} {r['record_fps']:11.1f} "
              f"{r['ratio']:6.2f} {r['end_to_end_fps']:11.1f} {r['mb']:6.1f}")
        emit(f"record {label}", baseline="bare render", baseline_value=r["bare_fps"],
             measured="record", measured_value=r["record_fps"], unit="fps", ratio=r["ratio"],
             target=">= 0.9")
    write_summary_rows("record_fps", args)


if __name__ == "__main__":
    main()
