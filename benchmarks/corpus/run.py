"""Calibrate every fetched corpus dataset with camlog and with plain OpenCV; print a table.

For each dataset: ``camlog import`` the folder into an MCAP log, ``camlog calibrate`` it
with the manifest's board and model, read ``calibration.json``, and compare with
``reference.reference_calibration`` and with the calibration the source publishes. A
dataset camlog (or OpenCV) cannot calibrate is a row saying so, with the message.

With ``--auto-order`` the pinhole datasets are calibrated with ``-k auto`` (the radial order
chosen by cross-validation over the views) and the model column names the order chosen.

    python -m benchmarks.corpus.run [--cache DIR] [--only NAME…] [--keep DIR] [--auto-order]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import cv2

from ..docs import add_write_docs, write_rows
from .manifest import CorpusError, Dataset, default_cache, load_manifest
from .reference import CameraResult, ReferenceResult, reference_calibration

HEADER = ("| dataset | model | views OpenCV / camlog | RMS px OpenCV / camlog | "
          "fx camlog − OpenCV | cx camlog − OpenCV | camlog vs published |")


@dataclass(frozen=True)
class CamlogResult:
    """What ``calibration.json`` says of the first (left) camera, and the pair."""

    cameras: list[CameraResult]
    baseline_m: float | None
    orders: list[str] = field(default_factory=list)  # with -k auto: each camera's order


def camlog_args(dataset: Dataset, *, auto_order: bool = False) -> list[str]:
    """``camlog calibrate`` options for the dataset's board, model and cameras (with
    ``auto_order``, ``-k auto`` for a plumb_bob dataset)."""
    board = dataset.board
    args = ["--size", board.size, "--square", str(board.square_m), "--pattern", board.pattern,
            "--model", dataset.model]
    if auto_order and dataset.model == "plumb_bob":
        args += ["-k", "auto"]
    if board.diameter_m is not None:
        args += ["--diameter", str(board.diameter_m)]
    if board.marker_m is not None:
        args += ["--marker", str(board.marker_m)]
    if board.dictionary is not None:
        args += ["--dictionary", board.dictionary]
    if board.legacy_pattern:
        args += ["--legacy-pattern"]
    cameras = ["--left", "/corpus/left", "--right", "/corpus/right"] if dataset.stereo else [
        "--camera", "/corpus"]
    return args + cameras


def _camlog(*args: str) -> None:
    done = subprocess.run([sys.executable, "-m", "camlog", *args], capture_output=True,
                          text=True, check=False)
    if done.returncode != 0:
        lines = (done.stderr.strip() or done.stdout.strip() or "no message").splitlines()
        raise CorpusError(f"camlog {args[0]} exit {done.returncode}: {lines[-1]}")


def camlog_calibration(dataset: Dataset, folder: Path, work: Path, *,
                       auto_order: bool = False, extra: tuple[str, ...] = ()) -> CamlogResult:
    """Import ``folder`` and calibrate it with camlog (``extra``: more options); the numbers
    of calibration.json (kept in ``work``/NAME_calibration)."""
    log = work / f"{dataset.name}.mcap"
    topic = "/corpus" if dataset.stereo else "/corpus/image_raw"
    _camlog("import", str(folder), "-o", str(log), "--topic", topic, "--rate", "1",
            "--overwrite", "--no-progress", *(["--stereo"] if dataset.stereo else []))
    out = work / f"{dataset.name}_calibration"
    _camlog("calibrate", str(log), *camlog_args(dataset, auto_order=auto_order), *extra, "-o",
            str(out), "--overwrite",
            "--no-report", "--no-progress")
    summary = json.loads((out / "calibration.json").read_text())
    cameras = []
    for camera in summary["cameras"]:
        values = {name: p["value"] for name, p in camera["parameters"].items()}
        cameras.append(CameraResult(camera["used_views"], camera["rms_px"], values["fx"],
                                    values["fy"], values["cx"], values["cy"]))
    stereo = summary.get("stereo")
    orders = [c["lens_order"]["chosen"] for c in summary["cameras"] if "lens_order" in c]
    return CamlogResult(cameras, stereo["baseline_m"] if stereo else None, orders)


def _published(dataset: Dataset, camlog: CamlogResult) -> str:
    ref = dataset.reference
    if ref is None:
        return "none published"
    left = camlog.cameras[0]
    parts = [f"fx {100 * (left.fx - ref.fx) / ref.fx:+.2f} %"
             if "compare cx, cy only" not in ref.model else "fx n/a (other model)",
             f"cx {left.cx - ref.cx:+.1f} px"]
    if ref.baseline_m is not None and camlog.baseline_m is not None:
        baseline_percent = 100 * (camlog.baseline_m - ref.baseline_m) / ref.baseline_m
        parts.append(f"baseline {baseline_percent:+.2f} %")
    return ", ".join(parts)


def row(dataset: Dataset, opencv: ReferenceResult | str, camlog: CamlogResult | str) -> str:
    """One markdown table row; a failed side shows its message."""
    kind = f"{dataset.model}{' stereo' if dataset.stereo else ''}, {dataset.board.pattern}"
    ocv = opencv if isinstance(opencv, ReferenceResult) else None
    cam = camlog if isinstance(camlog, CamlogResult) else None
    if cam is not None and cam.orders:
        kind += f" (-k auto: {', '.join(o.split(' ', 1)[1] for o in cam.orders)})"
    views = (f"{ocv.cameras[0].views if ocv else '—'} / {cam.cameras[0].views if cam else '—'}")
    rms = " / ".join("+".join(f"{c.rms_px:.3f}" for c in r.cameras) if r else "—"
                     for r in (ocv, cam))
    if ocv and cam:
        dfx = ", ".join(f"{c.fx - o.fx:+.1f}" for c, o in zip(cam.cameras, ocv.cameras,
                                                               strict=True))
        dcx = ", ".join(f"{c.cx - o.cx:+.1f}" for c, o in zip(cam.cameras, ocv.cameras,
                                                               strict=True))
    else:
        dfx = dcx = "—"
    published = f"camlog FAILED: {camlog}" if cam is None else _published(dataset, cam)
    if ocv is None:
        published += f"; OpenCV FAILED: {opencv}"
    return f"| {dataset.name} | {kind} | {views} | {rms} | {dfx} | {dcx} | {published} |"


def run(cache: Path, only: list[str] | None, keep: Path | None, *,
        auto_order: bool = False) -> list[str]:
    """The table's lines, one calibration at a time."""
    lines = [HEADER, "| " + " | ".join("---" for _ in range(7)) + " |"]
    with tempfile.TemporaryDirectory(prefix="camlog-corpus-") as temporary:
        work = keep or Path(temporary)
        work.mkdir(parents=True, exist_ok=True)
        for dataset in load_manifest():
            if only and dataset.name not in only:
                continue
            folder = cache / dataset.name
            if not folder.is_dir():
                lines.append(f"| {dataset.name} | not fetched: python -m "
                             f"benchmarks.corpus.fetch --cache {cache} |||||| ")
                continue
            opencv: ReferenceResult | str
            camlog: CamlogResult | str
            try:
                opencv = reference_calibration(dataset, folder)
            except (CorpusError, cv2.error) as error:
                opencv = str(error).strip().splitlines()[-1]
            try:
                camlog = camlog_calibration(dataset, folder, work, auto_order=auto_order)
            except (CorpusError, KeyError, OSError) as error:
                camlog = str(error)
            lines.append(row(dataset, opencv, camlog))
            print(lines[-1], file=sys.stderr, flush=True)
    return lines


def main() -> int:
    """Parse the command line, run, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", type=Path, default=default_cache())
    parser.add_argument("--only", nargs="+", metavar="NAME")
    parser.add_argument("--keep", type=Path, help="keep logs and calibrations in this folder")
    parser.add_argument("--auto-order", action="store_true",
                        help="calibrate the pinhole datasets with -k auto")
    add_write_docs(parser)
    args = parser.parse_args()
    lines = run(args.cache, args.only, args.keep, auto_order=args.auto_order)
    print("\n".join(lines))
    if args.write_docs:
        if args.auto_order:
            parser.error("--write-docs writes the table of the manifest's models: without "
                         "--auto-order")
        for line in lines[2:]:  # each calibrated dataset's row; the others keep theirs
            if "| not fetched: " not in line:
                write_rows("corpus", line.split("|")[1].strip(), [line])
    return 0


if __name__ == "__main__":
    sys.exit(main())
