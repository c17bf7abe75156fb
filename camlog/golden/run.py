"""Golden-log regression: small committed input logs and what every processor makes of them.

Inputs (``datasets/golden/NAME.mcap``, named by every input that shaped them) are recorded
only by :func:`record_inputs` (``camlog golden record``) and listed with their checksums
in ``manifest.json``: rendering differs across GL stacks, so checks always read the
committed files. :func:`compute_outputs` runs each input's jobs (calibrate, resync,
process) into a work folder and reduces what they wrote to artifacts: JSON numbers,
calibration YAML, first and last output frames as PNG, and short text summaries of the
output logs (topics, types, counts, log-time spans; never the bytes of compressed files).
:func:`compare` checks them against ``datasets/golden/expected/STEM/JOB/...`` within
:data:`~.tolerances.TOLERANCES`; :func:`update` rewrites the expected files that changed.
"""

from __future__ import annotations

import hashlib
import json
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import cv2

from replay.atomic import write_text_atomic
from replay.bounded import MAX_FILE_BYTES, json_loads, read_text
from replay.formats import open_reader
from replay.records import Scenario
from replay.topics import SCENARIO, read_record

from ..errors import GoldenError
from ..requests.calibrate import CalibrateRequest
from ..requests.processing import ProcessRequest, ResyncRequest
from .artifacts import (
    Artifacts,
    Difference,
    artifacts_equal,
    compare,
    dumps_json,
    update,
)
from .jobs import Calibrate, GoldenJob, Process, Resync

__all__ = [
    "INPUTS",
    "Artifacts",
    "Difference",
    "GoldenInput",
    "artifacts_equal",
    "check",
    "compare",
    "compute_outputs",
    "golden_dir",
    "in_checkout",
    "opencv_threads",
    "record_inputs",
    "regenerate",
    "update",
    "verify_inputs",
]

MANIFEST = "manifest.json"


def golden_dir() -> Path:
    """``datasets/golden``: the inputs, ``manifest.json`` and ``expected/``."""
    return Path(str(resources.files("camlog_datasets") / "golden"))


def in_checkout() -> bool:
    """Whether the golden files are a source checkout's ``datasets/golden`` (an editable
    install) rather than the copy an installed wheel carries."""
    datasets = golden_dir().parent
    return datasets.name == "datasets" and (datasets.parent / "pyproject.toml").is_file()


# --- golden inputs -------------------------------------------------------------------------

@dataclass(frozen=True)
class GoldenInput:
    """A recording of a built-in scenario, and the jobs run over it."""

    scenario: str
    seed: int
    width: int
    height: int
    frames: int
    jobs: tuple[GoldenJob, ...] = field(default=(), compare=False)

    @property
    def stem(self) -> str:
        """The file name without suffix: every recording option that shaped the log."""
        return f"{self.scenario}-seed{self.seed}-{self.width}x{self.height}-f{self.frames}"

    @property
    def file_name(self) -> str:
        """The golden log's file name."""
        return f"{self.stem}.mcap"

    @property
    def options(self) -> dict[str, Any]:
        """The recording options that shaped the log."""
        return {"frames": self.frames, "resolution": f"{self.width}x{self.height}"}

    @property
    def command(self) -> str:
        """The camlog command that records the log."""
        return (f"camlog record {self.scenario} --seed {self.seed} --frames {self.frames} "
                f"--resolution {self.width}x{self.height} -o {self.file_name}")


#: the golden set: ~16 held board poses to calibrate from, a pair to resync and calibrate,
#: and the red block
INPUTS: tuple[GoldenInput, ...] = (
    GoldenInput("mono_checkerboard", seed=0, width=640, height=480, frames=240, jobs=(
        Calibrate("calibrate", CalibrateRequest(size="7x6", square=0.01,
                                                camera=("/simple_camera",))),
        Process("edges", ProcessRequest(topic=("/simple_camera/image_raw",)),
                processors=("edges",)),
        Process("rectify", ProcessRequest(topic=("/simple_camera/image_raw",)),
                processors=("rectify",), calibration="calibrate/ost.yaml"),
    )),
    GoldenInput("stereo_unsynced", seed=0, width=640, height=480, frames=240, jobs=(
        Resync("resync", ResyncRequest(left="/unsynced/left", right="/unsynced/right")),
        Calibrate("calibrate", CalibrateRequest(size="7x6", square=0.01,
                                                left="/stereo_sync/left",
                                                right="/stereo_sync/right"),
                  log="resync/output.mcap"),
    )),
    GoldenInput("red_block", seed=0, width=640, height=480, frames=10, jobs=(
        Process("left", ProcessRequest(topic=("/stereo_camera/left/image_raw",)),
                processors=("red_pixels", "edges")),
        Process("right", ProcessRequest(topic=("/stereo_camera/right/image_raw",)),
                processors=("red_pixels", "edges")),
    )),
)


def _selected(only: Iterable[str] | None) -> list[GoldenInput]:
    if only is None:
        return list(INPUTS)
    wanted = set(only)
    unknown = wanted - {g.stem for g in INPUTS} - {g.scenario for g in INPUTS}
    if unknown:
        raise GoldenError(f"unknown golden input {', '.join(sorted(unknown))} (known: "
                          f"{', '.join(g.stem for g in INPUTS)})")
    return [g for g in INPUTS if g.stem in wanted or g.scenario in wanted]


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_manifest(inputs_dir: Path) -> dict[str, Any]:
    """``manifest.json`` of a golden folder; errors name the path."""
    path = inputs_dir / MANIFEST
    try:
        text = read_text(path, GoldenError,
                         missing_hint=" (camlog golden record writes it)")
        data = json_loads(text, str(path), GoldenError, max_bytes=MAX_FILE_BYTES)
    except json.JSONDecodeError as err:
        raise GoldenError(f"cannot read {path}: {err}") from None
    if not isinstance(data, dict) or not isinstance(data.get("inputs"), list):
        raise GoldenError(f"{path}: expected an object with an 'inputs' list")
    return data


def verify_inputs(inputs_dir: Path, only: Iterable[str] | None = None) -> list[str]:
    """Problems with the golden inputs: missing, not in the manifest, or changed bytes."""
    entries = {e.get("file"): e for e in read_manifest(inputs_dir)["inputs"]}
    problems = [f"{MANIFEST} lists {name}, which golden.INPUTS does not declare"
                for name in sorted(set(entries) - {g.file_name for g in INPUTS})]
    for golden in _selected(only):
        path, entry = inputs_dir / golden.file_name, entries.get(golden.file_name)
        if entry is None:
            problems.append(f"{golden.file_name} is not in {MANIFEST} (camlog golden record)")
            continue
        wanted = {"scenario": golden.scenario, "seed": golden.seed, "options": golden.options}
        for key, value in wanted.items():
            if entry.get(key) != value:
                problems.append(f"{golden.file_name}: {MANIFEST} says {key} "
                                f"{entry.get(key)!r}, golden.INPUTS says {value!r}")
        if not path.is_file():
            problems.append(f"{path} is missing")
        elif path.stat().st_size != entry.get("size_bytes"):
            problems.append(f"{path} has {path.stat().st_size} bytes, {MANIFEST} says "
                            f"{entry.get('size_bytes')}")
        elif _sha256(path) != entry.get("sha256"):
            problems.append(f"{path}: sha256 differs from {MANIFEST} (re-recorded by hand? "
                            "use camlog golden record)")
    return problems


def record_inputs(inputs_dir: Path, only: Iterable[str] | None = None) -> list[str]:
    """Re-record golden inputs and rewrite their manifest entries; one line per input."""
    from recorder.record import record
    from recorder.scenario import load_scenario

    inputs_dir.mkdir(parents=True, exist_ok=True)
    try:
        entries = {e["file"]: e for e in read_manifest(inputs_dir)["inputs"]}
    except GoldenError:
        entries = {}
    lines = []
    for golden in _selected(only):
        path = inputs_dir / golden.file_name
        scenario = load_scenario(golden.scenario, {
            "seed": golden.seed, "frames": golden.frames, "width": golden.width,
            "height": golden.height})
        record(scenario, path, overwrite=True, progress=False, compression="zstd")
        with open_reader(path) as reader:
            header = read_record(reader, SCENARIO, Scenario)
        if header is None:
            raise GoldenError(f"{path} has no {SCENARIO} record")
        old = entries.get(golden.file_name, {}).get("sha256")
        entry = {"file": golden.file_name, "scenario": golden.scenario, "seed": golden.seed,
                 "options": golden.options, "command": golden.command,
                 "renderer": header.renderer, "mujoco_version": header.mujoco_version,
                 "camlog_version": header.camlog_version, "format": "mcap",
                 "compression": "zstd", "sha256": _sha256(path),
                 "size_bytes": path.stat().st_size}
        entries[golden.file_name] = entry
        state = "new" if old is None else "unchanged" if old == entry["sha256"] else "changed"
        lines.append(f"{state:9s} {golden.file_name} ({entry['size_bytes']} bytes, "
                     f"{entry['renderer']}, MuJoCo {entry['mujoco_version']})")
    manifest = {
        "about": "Golden input logs, recorded only by `camlog golden record`; tests read "
                 "these files and check their sha256 first.",
        "inputs": [entries[g.file_name] for g in INPUTS if g.file_name in entries],
    }
    write_text_atomic(inputs_dir / MANIFEST, dumps_json(manifest))
    return lines


# --- computing, checking, regenerating -----------------------------------------------------

@contextmanager
def opencv_threads(count: int | None) -> Iterator[None]:
    """Run the block with OpenCV's own thread pool at ``count`` threads (None: unchanged)."""
    if count is None:
        yield
        return
    before = cv2.getNumThreads()
    cv2.setNumThreads(count)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


def compute_outputs(inputs_dir: Path, work_dir: Path, *, workers: int = 1,
                    only: Iterable[str] | None = None,
                    cv_threads: int | None = 1) -> Artifacts:
    """Run every job over the (verified) golden inputs; artifacts named ``STEM/JOB/FILE``.

    Job outputs (logs, calibration folders) are written below ``work_dir``. ``workers`` are
    camlog's threads per job; the artifacts do not depend on them. ``cv_threads`` pins
    OpenCV's own pool for the run: ``calibrateCamera`` sums in thread order, which moves fx
    by ~1e-6 px from run to run (far inside the tolerances) unless it runs on one thread.
    """
    selected = _selected(only)
    problems = verify_inputs(inputs_dir, [g.stem for g in selected])
    if problems:
        raise GoldenError(f"golden inputs in {inputs_dir}: {'; '.join(problems)}")
    artifacts: Artifacts = {}
    with opencv_threads(cv_threads):
        for golden in selected:
            folder = work_dir / golden.stem
            folder.mkdir(parents=True, exist_ok=True)
            for job in golden.jobs:
                log = inputs_dir / golden.file_name
                for name, value in job.run(log, folder, workers).items():
                    artifacts[f"{golden.stem}/{job.name}/{name}"] = value
    return artifacts


def _computed(inputs_dir: Path, work_dir: Path | None, workers: int,
              only: Sequence[str] | None) -> tuple[Artifacts, list[str]]:
    stems = [g.stem for g in _selected(only)]
    if work_dir is not None:
        return compute_outputs(inputs_dir, work_dir, workers=workers, only=stems), stems
    with tempfile.TemporaryDirectory(prefix="camlog-golden-") as tmp:
        return compute_outputs(inputs_dir, Path(tmp), workers=workers, only=stems), stems


def check(inputs_dir: Path, expected_dir: Path, *, diff_dir: Path | None,
          work_dir: Path | None = None, workers: int = 1,
          only: Sequence[str] | None = None) -> list[Difference]:
    """Verify, compute and compare: the differences from the expected outputs."""
    artifacts, stems = _computed(inputs_dir, work_dir, workers, only)
    return compare(expected_dir, artifacts, diff_dir, stems=stems)


def regenerate(inputs_dir: Path, expected_dir: Path, *, work_dir: Path | None = None,
               workers: int = 1, only: Sequence[str] | None = None) -> list[str]:
    """Verify, compute and :func:`update` the expected outputs; what changed, per line."""
    artifacts, stems = _computed(inputs_dir, work_dir, workers, only)
    return update(expected_dir, artifacts, stems=stems)
