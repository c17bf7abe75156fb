"""Golden jobs: run one camlog step over a golden input and reduce its outputs to artifacts.

A job writes below ``FOLDER/NAME`` (FOLDER is the input's work folder) and returns its
artifacts named relative to that folder. Artifacts hold what a regression would change and
nothing that is brittle: numbers, calibration YAML, the first and last output frames, and
text summaries of output logs (topics, types, counts, log-time spans) instead of their
compressed bytes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from camlog.logs.info import summarize
from processors.registry import configure
from processors.spec import Configured
from replay.formats import open_reader
from replay.messages import Image, PointStamped
from replay.records import CalibrationSummary, ResyncStats, to_json
from replay.topics import ResyncTopics, read_record

from ..errors import GoldenError
from ..requests.calibrate import CalibrateRequest
from ..requests.processing import ProcessRequest, ResyncRequest
from .artifacts import Artifacts, dumps_json

__all__ = [
    "Calibrate",
    "GoldenJob",
    "Process",
    "Resync",
    "calibration_numbers",
    "log_summary",
    "pair_table",
]


class GoldenJob(Protocol):
    """One step over a golden input; writes below ``folder / name`` and returns artifacts
    named relative to that folder."""

    @property
    def name(self) -> str:
        """The job's name: its folder and the prefix of its artifacts."""
        ...

    def run(self, log: Path, folder: Path, workers: int) -> Artifacts:
        """Run the job on ``log`` below ``folder``; its artifacts."""
        ...


def _json(value: Any) -> Any:
    """A JSON artifact exactly as it reads back from its file."""
    return json.loads(dumps_json(value))


def log_summary(path: Path) -> str:
    """Topics of a log with type, count, log-time span and stream detail, one per line."""
    with open_reader(path) as reader:
        summary = summarize(reader)
    lines = [f"{summary.message_count} messages on {len(summary.topics)} topics"]
    for t in summary.topics:
        span = f"{t.first_ns}..{t.last_ns}" if t.first_ns is not None else "-"
        lines.append(f"{t.name}  {t.msgtype}  {t.count}  {span}  {t.detail}".rstrip())
    return "\n".join(lines) + "\n"


#: the topics of a resync output at the default prefix
SYNCED = ResyncTopics()

#: calibration.json keys kept per camera and for the pair (inputs and figures left out)
CAMERA_KEYS = ("namespace", "image_topic", "width", "height", "frames", "distinct_frames",
               "boards_found", "candidate_views", "selected_views", "used_views", "rejected",
               "rms_px", "distortion_model", "parameters", "cross_validation_px",
               "max_projection_difference_vs_truth_px",
               "max_projection_difference_vs_truth_covered_px",
               "max_projection_difference_vs_truth_aligned_px",
               "max_projection_difference_vs_truth_covered_aligned_px")
STEREO_KEYS = ("rms_px", "epipolar_rms_px", "baseline_m", "baseline_std_m", "square_m",
               "rotation_deg", "translation_m", "joint_views")


def calibration_numbers(summary: CalibrationSummary) -> dict[str, Any]:
    """The key numbers of ``calibration.json``: views, RMS, parameters with their sigma."""
    cameras = []
    for camera in summary.cameras:
        data = to_json(camera)
        entry = {k: data[k] for k in CAMERA_KEYS if k in data}
        entry["parameters"] = {name: {"value": p.value, "std": p.std}
                               for name, p in camera.parameters.items()}
        cameras.append(entry)
    out: dict[str, Any] = {"cameras": cameras}
    if summary.stereo is not None:
        stereo = to_json(summary.stereo)
        out["stereo"] = {k: stereo[k] for k in STEREO_KEYS}
    return out


@dataclass(frozen=True)
class Calibrate:
    """``camlog calibrate`` as ``request`` asks (its log, output and progress set here)."""

    name: str
    request: CalibrateRequest
    log: str | None = None  # another job's output log, relative to the input's folder

    def run(self, log: Path, folder: Path, workers: int) -> Artifacts:
        """Calibrate and keep the YAML files, the key numbers and the log summary."""
        from ..calibrate.flow import calibrate_log

        out = folder / self.name
        calibrate_log(replace(self.request, log=folder / self.log if self.log else log,
                              output=out, overwrite=True, progress=False), workers=workers)
        yamls = ("left.yaml", "right.yaml") if self.request.left else ("ost.yaml",)
        return {name: (out / name).read_text() for name in yamls} | {
            "calibration.json": _json(calibration_numbers(CalibrationSummary.from_json_text(
                (out / "calibration.json").read_text()))),
            "calibration_mcap.txt": log_summary(out / "calibration.mcap"),
        }


@dataclass(frozen=True)
class Resync:
    """``camlog resync`` as ``request`` asks: the pair table rebuilt from the output log, its
    stats and summary."""

    name: str
    request: ResyncRequest

    def run(self, log: Path, folder: Path, workers: int) -> Artifacts:
        """Resync and keep the pair table, the stats and the log summary."""
        from ..processing.resync_log import resync_log

        output = folder / self.name / "output.mcap"
        output.parent.mkdir(parents=True, exist_ok=True)
        resync_log(replace(self.request, log=log, output=output, overwrite=True))
        left, right = self.request.left, self.request.right
        return {"pairs.json": _json(pair_table(log, output, left, right)),
                "stats.json": _json(_stats(output)),
                "output.txt": log_summary(output)}


def _image_stamps(path: Path, topic: str) -> list[int]:
    with open_reader(path) as reader:
        return [r.message.stamp_ns for r in reader.messages([topic])
                if isinstance(r.message, Image)]


def pair_table(log: Path, output: Path, left: str, right: str,
               topics: ResyncTopics = SYNCED) -> dict[str, Any]:
    """Per pair (left stamp, right stamp, output stamp), and the unpaired input stamps.

    The output holds the common stamp (the later one) and ``x = right - left`` in seconds,
    which is exact in float64 for offsets under a second; the two input stamps follow.
    """
    offsets: dict[int, int] = {}
    with open_reader(output) as reader:
        for record in reader.messages([topics.offset]):
            if isinstance(record.message, PointStamped):
                offsets[record.message.stamp_ns] = round(float(record.message.point[0]) * 1e9)
    rows = []
    for out_ns in _image_stamps(output, topics.left.image_raw):
        offset = offsets[out_ns]
        left_ns, right_ns = (out_ns - offset, out_ns) if offset >= 0 else (out_ns,
                                                                             out_ns + offset)
        rows.append([left_ns, right_ns, out_ns])
    paired = [{r[0] for r in rows}, {r[1] for r in rows}]
    inputs = [_image_stamps(log, f"{ns.rstrip('/')}/image_raw") for ns in (left, right)]
    return {"columns": ["left_stamp_ns", "right_stamp_ns", "output_stamp_ns"], "pairs": rows,
            "left_unpaired_stamps_ns": [s for s in inputs[0] if s not in paired[0]],
            "right_unpaired_stamps_ns": [s for s in inputs[1] if s not in paired[1]]}


def _stats(output: Path, topics: ResyncTopics = SYNCED) -> Any:
    with open_reader(output) as reader:
        stats = read_record(reader, topics.stats, ResyncStats)
    if stats is None:
        raise GoldenError(f"{output} has no {topics.stats}")
    return to_json(stats)


@dataclass(frozen=True)
class Process:
    """``camlog process`` as ``request`` asks, with the registry's ``processors``: first and
    last output frames, the red centroid and edge-pixel tracks per frame, and the output
    log's summary."""

    name: str
    request: ProcessRequest
    processors: tuple[str, ...]
    calibration: str | None = None  # for rectify: another job's YAML, relative to the folder

    def build(self, folder: Path) -> list[Configured]:
        """The job's processors, configured (rectify with the calibration file)."""
        from replay.calibration_yaml import load_calibration

        options: dict[str, dict[str, Any]] = {}
        if self.calibration is not None:
            info = load_calibration(folder / self.calibration).camera_info
            options["rectify"] = {"camera_info": info}
        return [configure(name, **options.get(name, {})) for name in self.processors]

    def run(self, log: Path, folder: Path, workers: int) -> Artifacts:
        """Process and keep the output frames, tracks and the log summary."""
        from ..processing.process_log import process_log

        output = folder / self.name / "output.mcap"
        output.parent.mkdir(parents=True, exist_ok=True)
        result = process_log(replace(self.request, log=log, output=output, overwrite=True,
                                     workers=workers, processors=tuple(self.build(folder))))
        topics = [o.topic for o in result.outputs]
        return _frame_artifacts(output, topics) | {"output.txt": log_summary(output)}


def _frame_artifacts(output: Path, topics: list[str]) -> Artifacts:
    first: dict[str, np.ndarray] = {}
    last: dict[str, np.ndarray] = {}
    centroid: dict[int, tuple[float, float]] = {}
    counts: list[tuple[int, int]] = []
    edges: list[dict[str, int]] = []
    with open_reader(output) as reader:
        for record in reader.messages(sorted(topics)):
            leaf, message = record.topic.rsplit("/", 1)[-1], record.message
            if isinstance(message, Image):
                pixels = np.array(message.pixels)  # a copy: views pin the reader's chunk
                first.setdefault(leaf, pixels)
                last[leaf] = pixels
                if leaf == "edges":
                    edges.append({"stamp_ns": message.stamp_ns,
                                  "edge_pixels": int(np.count_nonzero(message.pixels))})
            elif isinstance(message, PointStamped) and leaf == "red_centroid":
                centroid[message.stamp_ns] = (float(message.point[0]), float(message.point[1]))
            elif isinstance(message, PointStamped) and leaf == "red_count":
                counts.append((message.stamp_ns, round(float(message.point[0]))))
    out: Artifacts = {}
    for leaf, pixels in first.items():
        out[f"{leaf}-first.png"], out[f"{leaf}-last.png"] = pixels, last[leaf]
    if counts:
        out["red_centroid.json"] = _json({"frames": [
            {"stamp_ns": s, "u_px": centroid.get(s, (None, None))[0],
             "v_px": centroid.get(s, (None, None))[1], "count": n} for s, n in counts]})
    if edges:
        out["edges.json"] = _json({"frames": edges})
    return out


