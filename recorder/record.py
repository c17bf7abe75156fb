"""Record a scenario: render every camera frame and write images, camera_info and truth.

Rendering runs on the calling thread; warping, noise, serialization and writing run on a
worker thread behind a bounded queue so that they overlap rendering.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from tqdm import tqdm

from replay import Image, PoseStamped, open_writer
from replay._version import VERSION
from replay.formats import LogWriter
from replay.formats.background import BackgroundWriter
from replay.geometry import invert, quat_xyzw_from_rotation
from replay.records import RenderView, Scenario, ScenarioCamera, ScenarioDrift, ScenarioLatency
from replay.topics import SCENARIO, CameraTopics

from .clock import Shot, schedule
from .errors import RecorderError
from .exposure import rendered_shots
from .motion import plan_trajectory
from .multiview import CameraOptics, MultiViewOptics, plan_camera_optics
from .render import SceneRenderer, gl_backend
from .rig_motion import CameraPoses, plan_rig_path
from .scenario import ScenarioSpec
from .targets import target_record

#: seed streams, so that changing one aspect of a scenario does not reshuffle the others
MOTION_STREAM, CLOCK_STREAM, NOISE_STREAM, RIG_STREAM = 1, 2, 3, 4


@dataclass
class RecordResult:
    """What a recording produced."""

    path: Path
    frames: dict[str, int]  # camera name -> frames written
    dropped: dict[str, list[int]]  # camera name -> dropped frame indices
    wall_s: float  # everything, setup included
    loop_s: float = 0.0  # rendering and writing frames, from the first shot to the closed log
    topics: list[str] = field(default_factory=list)
    storage: str = ""  # format and compression, e.g. "mcap, zstd chunks"

    @property
    def fps(self) -> float:
        """Frames per second end to end."""
        return sum(self.frames.values()) / self.wall_s if self.wall_s > 0 else 0.0

    @property
    def loop_fps(self) -> float:
        """Frames per second of the render-and-write loop (setup excluded)."""
        return sum(self.frames.values()) / self.loop_s if self.loop_s > 0 else 0.0


def rng_for(scenario: ScenarioSpec, stream: int, index: int) -> np.random.Generator:
    """The random generator of one seed stream (motion, clock, noise) and index."""
    return np.random.default_rng([scenario.seed, stream, index])


def _views_record(optics: CameraOptics) -> dict[str, Any]:
    """The pinhole views a multi-view camera was rendered from (nothing for one view)."""
    if not isinstance(optics, MultiViewOptics):
        return {}
    views = [RenderView(size=(v.width, v.height), focal_px=v.focal_px,
                        principal_px=(v.cx, v.cy), camera_from_view=v.camera_from_view)
             for v in optics.views]
    return {"render_views": views, "samples_per_side": optics.samples_per_side}


def scenario_record(
    scenario: ScenarioSpec, optics: list[CameraOptics], dropped: dict[int, np.ndarray]
) -> Scenario:
    """Everything that shaped the recording, stored in the log (``/camlog/scenario``)."""
    import mujoco

    cameras = [
        ScenarioCamera(
            name=camera.name, namespace=camera.namespace, frame_id=camera.frame_id,
            width=camera.model.width, height=camera.model.height, k=camera.model.k,
            distortion_model=camera.model.distortion_model, d=camera.model.d,
            world_from_camera=camera.world_from_camera,
            render_size=optics[index].render_sizes[0], supersample=optics[index].supersample,
            dropped_frames=dropped[index].tolist(), **_views_record(optics[index]),
            exposure_s=camera.exposure_s or None)
        for index, camera in enumerate(scenario.cameras)
    ]
    targets = [target_record(target) for target in scenario.targets]
    namespaces = {c.name: c.namespace for c in scenario.cameras}
    drifts = [ScenarioDrift(camera=d.camera, namespace=namespaces[d.camera], axis=d.axis,
                            degrees=d.degrees, start_s=d.start_s,
                            start_stamp_ns=scenario.start_stamp_ns + round(d.start_s * 1e9))
              for d in scenario.drifts]
    latencies = [ScenarioLatency(camera=latency.camera, namespace=namespaces[latency.camera],
                                 latency_ms=latency.latency_ms, start_s=latency.start_s)
                 for latency in scenario.latencies]
    return Scenario(
        scenario=scenario.name, source=scenario.source, seed=scenario.seed,
        camlog_version=VERSION, mujoco_version=mujoco.__version__,
        renderer=f"mujoco/{gl_backend()}", spec=scenario.spec, cameras=cameras,
        targets=targets, drifts=drifts or None, latencies=latencies or None)


class _Pipeline:
    """The log writer on a worker thread (:class:`~replay.formats.background.BackgroundWriter`,
    which opens, uses and closes it on that one thread, as some storages, SQLite, require)
    that also finishes frames there (warp, noise, encoding) before writing them."""

    def __init__(
        self, scenario: ScenarioSpec, optics: list[CameraOptics], open_log: Callable[[], LogWriter]
    ) -> None:
        self.scenario = scenario
        self.optics = optics
        self.noise = [rng_for(scenario, NOISE_STREAM, i) for i in range(len(optics))]
        #: per camera, its last render and the image the optics made of it: a held pose's
        #: render comes again, the same array, for each of its frames (one thread reads this)
        self._warped: list[tuple[np.ndarray | None, np.ndarray | None]] = \
            [(None, None)] * len(optics)
        self._log = BackgroundWriter(open_log, max_queued=6)

    def put(self, item: tuple[Shot, np.ndarray, list[np.ndarray]]) -> None:
        """Queue a rendered shot (with its true target poses) to be finished and written."""
        self._log.submit(partial(self._write, shot=item[0], rendered=item[1], truth=item[2]))

    def finish(self) -> None:
        """Write what is queued, close the log and raise the worker's error, if any."""
        self._log.close()

    def abort(self) -> None:
        """Drop what is queued and the partial log."""
        self._log.abort()

    def _write(
        self, writer: LogWriter, shot: Shot, rendered: np.ndarray, truth: list[np.ndarray]
    ) -> None:
        camera = self.scenario.cameras[shot.camera_index]
        stamp_ns = self.scenario.start_stamp_ns + round(shot.stamp_s * 1e9)
        last, warped = self._warped[shot.camera_index]
        if rendered is last and warped is not None:
            pixels = warped
        else:
            pixels = self.optics[shot.camera_index].apply(rendered)
            pixels.flags.writeable = False
            self._warped[shot.camera_index] = (rendered, pixels)
        if camera.noise_std > 0:
            rng = self.noise[shot.camera_index]
            noisy = pixels.astype(np.float32)
            noisy += rng.standard_normal(pixels.shape, dtype=np.float32) * camera.noise_std
            pixels = np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
        if camera.encoding == "bgr8":
            pixels = cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR)
        elif camera.encoding == "mono8":
            pixels = cv2.cvtColor(pixels, cv2.COLOR_RGB2GRAY)
        write, topics = writer.write, CameraTopics(camera.namespace)
        write(topics.image_raw, Image(stamp_ns, camera.frame_id, camera.encoding, pixels))
        write(topics.camera_info, camera.model.camera_info(
            stamp_ns=stamp_ns, frame_id=camera.frame_id, baseline_tx=camera.baseline_tx))
        for target, camera_from_target in zip(self.scenario.targets, truth, strict=True):
            write(topics.ground_truth(target.name), PoseStamped(
                stamp_ns, camera.frame_id, camera_from_target[:3, 3],
                quat_xyzw_from_rotation(camera_from_target[:3, :3])))


def record(
    scenario: ScenarioSpec,
    output: str | Path,
    *,
    fmt: str | None = None,
    overwrite: bool = False,
    progress: bool | None = None,
    **writer_options: Any,
) -> RecordResult:
    """Render ``scenario`` and write its log to ``output`` (atomically)."""
    output = Path(output)
    started = time.perf_counter()
    optics = [plan_camera_optics(c.model, c.supersample) for c in scenario.cameras]
    frame_counts = scenario.frame_counts
    duration_s = max(n / c.rate_hz + c.phase_s
                     for n, c in zip(frame_counts, scenario.cameras, strict=True))
    trajectories = [
        plan_trajectory(t, scenario.cameras, duration_s, rng_for(scenario, MOTION_STREAM, i))
        for i, t in enumerate(scenario.targets)
    ]
    camera_poses = CameraPoses(scenario.cameras, scenario.drifts, None if scenario.rig_motion
                               is None else plan_rig_path(scenario.rig_motion, duration_s,
                                                          rng_for(scenario, RIG_STREAM, 0)))
    shots, dropped = schedule(
        scenario.cameras, frame_counts,
        [rng_for(scenario, CLOCK_STREAM, i) for i in range(len(scenario.cameras))],
        scenario.latencies,
    )
    renderer = SceneRenderer(scenario, optics)  # first: it sets MUJOCO_GL before the import
    header = scenario_record(scenario, optics, dropped).to_message()
    metadata = {"scenario": scenario.name, "seed": str(scenario.seed), "version": VERSION,
                "renderer": f"mujoco/{gl_backend()}"}

    # the scenario record comes first, before the stamp of a camera stamping early
    first_ns = scenario.start_stamp_ns + min([0, *(round(latency.latency_s * 1e9)
                                                   for latency in scenario.latencies)])
    storage: list[str] = []

    def open_log() -> LogWriter:
        writer = open_writer(output, fmt=fmt, overwrite=overwrite, live=True,
                             **writer_options)
        storage.append(f"{writer.format_name}, {writer.compression}")
        try:
            writer.write(SCENARIO, header, log_time_ns=first_ns)
            writer.set_metadata("camlog", metadata)
        except BaseException:
            writer.abort()
            raise
        return writer

    frames = dict.fromkeys((c.name for c in scenario.cameras), 0)
    try:
        loop_started = time.perf_counter()
        # the bar first: once the pipeline has opened the log, nothing may come between it
        # and the block that drops the partial log on an error or Ctrl-C
        bar = tqdm(total=len(shots), unit="frame", desc=f"record {scenario.name}",
                   disable=None if progress is None else not progress, leave=False)
        try:
            pipeline = _Pipeline(scenario, optics, open_log)
            try:
                for shot, rendered, poses in rendered_shots(renderer, scenario.cameras,
                                                            scenario.targets, trajectories,
                                                            shots, camera_poses=camera_poses):
                    camera_from_world = invert(camera_poses.world_from_camera(
                        shot.camera_index, shot.t_s))
                    truth = [camera_from_world @ p for p in poses]
                    pipeline.put((shot, rendered, truth))
                    frames[scenario.cameras[shot.camera_index].name] += 1
                    bar.update()
                pipeline.finish()
                loop_s = time.perf_counter() - loop_started
            except BaseException:
                pipeline.abort()
                raise
        finally:
            bar.close()
    finally:
        renderer.close()
    return RecordResult(
        path=output,
        frames=frames,
        dropped={c.name: dropped[i].tolist() for i, c in enumerate(scenario.cameras)},
        wall_s=time.perf_counter() - started,
        loop_s=loop_s,
        storage=storage[0],
        topics=sorted({SCENARIO} | {
            t for c in scenario.cameras for topics in [CameraTopics(c.namespace)]
            for t in (topics.image_raw, topics.camera_info,
                      *(topics.ground_truth(x.name) for x in scenario.targets))
        }),
    )


__all__ = ["RecordResult", "RecorderError", "record"]
