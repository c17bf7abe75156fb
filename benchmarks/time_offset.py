"""Time offsets between cameras measured from their images, against the simulator's truth.

Three cases, each over many seeds:

- **board**: ``stereo_moving_board`` (a waved board, both cameras exposing at the same
  instants, no motion blur) with the right camera stamping 0, 3, 17, 33 or -10 ms late; the
  offset measured by ``camlog resync --estimate-offset`` from the board
  (:func:`processors.time_offset.estimate_board_offset`): the median and 95th percentile of
  ``|error|`` per offset and the RMS of ``error / sigma`` (1 when the sigma is honest).
- **natural**: ``stereo_moving_rig`` (a rig carried over a textured scene) with the same
  latencies, the rig's motion scaled per seed (0.25, 0.5, 1 or 1.5 times the scenario's), the
  offset measured from natural features (:func:`processors.time_offset.estimate_feature_
  offset`): the same figures, and each log's error against how fast its features move across
  the rows (the RMS of the rig's rows' speed, from its true path), drawn to
  ``docs/time_offset_natural.png``.
- **rig**: ``camlog calibrate`` of the board logs stamped 17 ms late (the offset measured and
  the views paired by it), of the same logs with true stamps, and of the late logs paired by
  their stamps (``resync``: every left frame with the right frame stamped nearest, then
  calibrated as one instant each); and, for what the stamps cost a solver that trusts them,
  ``cv2.stereoCalibrate`` of the late and the true logs' stamp pairs, intrinsics fixed at the
  truth (:func:`opencv_rigs`): the baseline's and the rotation's error against the truth,
  medians over the seeds.

A latency changes nothing but stamps (the recorder draws no random number for it: the same
seed renders the same images), so each seed is rendered once with true stamps and each
offset's log is that recording with the right camera's messages re-stamped as
``camlog record --latency right:MS`` stamps them (:func:`restamped`; the scenario record
lists the latency); ``tests/benchmarks/test_time_offset.py`` checks that the two agree
message for message. The same seeds serve every offset. Recordings are cached in ``--cache``
(outside the repository, named by their inputs), each log's result appended to ``--keep``
(one JSON line, read back by a later run: a run can be resumed). Run with ``nice -n 10``::

    python -m benchmarks.time_offset [--seeds 20] [--cases board,natural,rig] [--write-docs]
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import json
import math
import re
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from camlog.cli import main as camlog
from recorder.record import RIG_STREAM, rng_for
from recorder.rig_motion import plan_rig_path
from recorder.scenario import load_scenario
from replay.atomic import write_bytes_atomic
from replay.records import TimeOffset

from .docs import PAGE, add_write_docs, markdown_table, write_table

OFFSETS_MS = (0.0, 3.0, 17.0, 33.0, -10.0)
RIG_OFFSET_MS = 17.0
#: pairs spread over the log that the OpenCV rig is solved from (its dense solve grows with
#: the cube of the views)
OPENCV_PAIRS = 40
#: ``cornerSubPix``'s window (half sizes, px) for the OpenCV rig: a square of the board at
#: 320x240 spans about 10 px
OPENCV_WINDOW = (4, 4)
#: the natural case's rig motion, as multiples of the scenario's, cycled over the seeds
MOTION_SCALES = (0.25, 0.5, 1.0, 1.5)
DURATION_S = {"board": 8.0, "natural": 6.0}
RESOLUTION = "320x240"
FIRST_SEED = 1000
LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"
CAMERAS = ["--left", LEFT, "--right", RIGHT]
BOARD = ["-s", "7x6", "-q", "0.01"]
DEFAULT_CACHE = Path.home() / ".cache" / "camlog" / "time_offset"
FIGURE = PAGE.parent / "time_offset_natural.png"


@dataclass(frozen=True)
class Case:
    """One log of the sweep: its case, seed and the right camera's latency."""

    kind: str  # board | natural
    seed: int
    offset_ms: float

    @property
    def scale(self) -> float:
        """The natural case's rig motion, as a multiple of the scenario's."""
        return MOTION_SCALES[self.seed % len(MOTION_SCALES)] if self.kind == "natural" else 1.0

    @property
    def key(self) -> str:
        """The name of its recording and of its result line."""
        return f"{self.kind}-s{self.seed}-o{self.offset_ms:+g}-x{self.scale:g}"


def _spec(case: Case, folder: Path) -> Path:
    """The scenario spec of a case: the natural one with its rig motion scaled, the board
    without motion blur (sub-frame renders would multiply the rendering time)."""
    name = _spec_name(case)
    text = (PAGE.parents[1] / "datasets" / "scenarios" / f"{name}.toml").read_text()
    if case.kind == "board":
        assert text.count("exposure_s = 0.004\n") == 2, f"{name}.toml: expected two exposures"
        text = text.replace("exposure_s = 0.004\n", "")
    if case.kind == "natural":
        scenario = load_scenario(name)
        assert scenario.rig_motion is not None
        for key, values in (("translation_m", scenario.rig_motion.translation_m),
                            ("rotation_rad", scenario.rig_motion.rotation_rad)):
            old = f"{key} = [{', '.join(f'{v:g}' for v in values)}]"
            assert old in text, f"{name}.toml: expected {old!r}"
            scaled = ", ".join(f"{v * case.scale:g}" for v in values)
            text = text.replace(old, f"{key} = [{scaled}]")
    path = folder / f"{case.key}.toml"
    path.write_text(text)
    return path


def recording(case: Case, cache: Path) -> Path:
    """The case's log in ``cache``: its seed rendered once with true stamps, re-stamped with
    the case's latency (both made unless already there)."""
    true = Case(case.kind, case.seed, 0.0)
    rendered = cache / f"{true.key}-{RESOLUTION}.mcap"
    if not rendered.exists():
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()):
            code = camlog(["record", str(_spec(true, Path(tmp))), "-o", str(rendered),
                           "--seed", str(case.seed), "--duration",
                           f"{DURATION_S[case.kind]:g}", "--resolution", RESOLUTION,
                           "--no-progress"])
        if code:
            raise SystemExit(f"error: recording {true.key} failed")
    if case.offset_ms == 0.0:
        return rendered
    path = cache / f"{case.key}-{RESOLUTION}.mcap"
    if not path.exists():
        restamped(rendered, path, camera="right", latency_ms=case.offset_ms)
    return path


def restamped(log: Path, out: Path, *, camera: str, latency_ms: float) -> None:
    """A copy of a recording with true stamps whose ``camera`` stamps its messages (image,
    camera_info, ground truth) ``latency_ms`` after their exposure, as ``camlog record
    --latency CAMERA:MS`` makes it: messages in stamp order (log time = stamp), the latency
    in the scenario record."""
    from replay import open_reader, open_writer
    from replay.records import Scenario, ScenarioLatency
    from replay.topics import SCENARIO

    shift_ns = round(latency_ms * 1e6)
    with open_reader(log) as reader:
        messages = [(raw.topic, raw.log_time_ns, reader.decode(raw))
                    for raw in reader.raw_messages()]
    (record,) = [Scenario.from_message(m) for t, _, m in messages if t == SCENARIO]
    (moved,) = [c for c in record.cameras if c.name == camera]
    record = dataclasses.replace(record, latencies=[
        ScenarioLatency(camera=camera, namespace=moved.namespace, latency_ms=latency_ms)])
    out_messages: list[tuple[str, int, Any]] = []
    for topic, log_time_ns, message in messages:
        if topic == SCENARIO:
            out_messages.append((topic, log_time_ns + min(shift_ns, 0), record.to_message()))
        elif topic.startswith(moved.namespace + "/"):
            stamped: Any = message
            stamp = int(stamped.stamp_ns) + shift_ns
            out_messages.append((topic, stamp, dataclasses.replace(stamped, stamp_ns=stamp)))
        else:
            out_messages.append((topic, log_time_ns, message))
    out_messages.sort(key=lambda item: item[1])
    with open_writer(out) as writer:
        for topic, log_time_ns, message in out_messages:
            writer.write(topic, message, log_time_ns=log_time_ns)


def row_speed_px_s(case: Case) -> float:
    """How fast the natural case's features move across the rows (RMS over its duration,
    px/s): the rig's pitch rate times the focal length (the turn about its x axis moves
    every point of a far scene down the image at ``f w_x``), from its true path."""
    scenario = load_scenario(_spec_name(case), {"seed": case.seed})
    assert scenario.rig_motion is not None
    motion = scenario.rig_motion
    scaled = type(motion)(motion.segment_s, motion.translation_m * case.scale,
                          motion.rotation_rad * case.scale)
    path = plan_rig_path(scaled, DURATION_S["natural"], rng_for(scenario, RIG_STREAM, 0))
    model = scenario.cameras[0].model
    focal = model.fx * int(RESOLUTION.split("x", maxsplit=1)[0]) / model.width
    times = np.arange(0.0, DURATION_S["natural"], 1 / 30)
    rates = []
    for t in times:
        a, b = path.rest_from_moved(float(t)), path.rest_from_moved(float(t) + 1e-3)
        turn = a[:3, :3].T @ b[:3, :3]
        rates.append((turn[2, 1] - turn[1, 2]) / 2 / 1e-3)  # rad/s about x
    return float(focal * math.sqrt(np.mean(np.square(rates))))


def case_of(key: str) -> Case:
    """The case a result's key names (:attr:`Case.key`)."""
    found = re.fullmatch(r"(?P<kind>[a-z]+)-s(?P<seed>\d+)-o(?P<offset>[-+][\d.]+)-x[\d.]+",
                         key)
    if found is None:
        raise ValueError(f"not a case's key: {key!r}")
    return Case(found["kind"], int(found["seed"]), float(found["offset"]))


def _spec_name(case: Case) -> str:
    return "stereo_moving_rig" if case.kind == "natural" else "stereo_moving_board"


def measure(case: Case, cache: Path) -> dict[str, Any]:
    """The offset ``resync --estimate-offset`` measures in the case's log (or why not)."""
    log = recording(case, cache)
    with tempfile.TemporaryDirectory() as tmp:
        result = Path(tmp) / "offset.json"
        board = BOARD if case.kind == "board" else []
        errors = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(errors):
            code = camlog(["resync", str(log), *CAMERAS, *board, "--estimate-offset",
                           "--offset-file", str(result), "--no-progress"])
        if code:
            return {"key": case.key, "why_not": errors.getvalue().strip()}
        offset = TimeOffset.from_json_text(result.read_text())
    out = {"key": case.key, "offset_ms": offset.offset_ms, "std_ms": offset.std_ms,
           "error_ms": offset.offset_ms - case.offset_ms, "frames": offset.frames}
    if case.kind == "natural":
        out["row_speed_px_s"] = row_speed_px_s(case)
    return out


def _calibrated(log: Path, folder: Path, *options: str) -> dict[str, Any]:
    """``calibration.json`` of ``camlog calibrate`` (or ``why_not``: its error line)."""
    errors = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(errors):
        code = camlog(["calibrate", str(log), *BOARD, "-o", str(folder), "--no-report",
                       "--no-progress", "--overwrite", *options])
    if code:
        return {"why_not": errors.getvalue().strip()}
    summary: dict[str, Any] = json.loads((folder / "calibration.json").read_text())
    return summary


def _rig_errors(summary: dict[str, Any]) -> dict[str, float]:
    """The baseline's error (%) and the rotation's (degrees; the true rig turns by none)."""
    if "stereo" not in summary:
        return {key: value for key, value in summary.items() if key == "why_not"}
    stereo = summary["stereo"]
    return {"baseline_error_percent": abs(stereo["truth"]["baseline_error_percent"]),
            "rotation_error_deg": stereo["rotation_deg"], "joint_views": stereo["joint_views"]}


def calibrate_rig(seed: int, cache: Path) -> dict[str, Any]:
    """The rig of one seed calibrated three ways (see the module's text)."""
    late = recording(Case("board", seed, RIG_OFFSET_MS), cache)
    true = recording(Case("board", seed, 0.0), cache)
    out: dict[str, Any] = {"key": f"rig-s{seed}"}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        estimated = _calibrated(late, folder / "estimated", *CAMERAS)
        out["estimated"] = _rig_errors(estimated)
        if "stereo" in estimated:
            right = next(c for c in estimated["cameras"] if c["namespace"] == RIGHT)
            out["estimated"]["offset_error_ms"] = right["time_offset"].get("error_ms")
        out["true"] = _rig_errors(_calibrated(true, folder / "true", *CAMERAS))
        synced = folder / "synced.mcap"
        with contextlib.redirect_stdout(io.StringIO()):
            camlog(["resync", str(late), "-o", str(synced), *CAMERAS])
        out["stamps"] = _rig_errors(_calibrated(
            synced, folder / "stamps", "--left", "/stereo_sync/left", "--right",
            "/stereo_sync/right", "--time-offset", "off"))
    return out


def opencv_rigs(seed: int, cache: Path) -> dict[str, Any]:
    """The rig of one seed as ``cv2.stereoCalibrate`` finds it from the stamp pairs of the
    log with true stamps and of the log stamped late (:func:`opencv_rig`)."""
    return {"key": f"opencv-s{seed}",
            "opencv_true": opencv_rig(recording(Case("board", seed, 0.0), cache)),
            "opencv_stamps": opencv_rig(recording(Case("board", seed, RIG_OFFSET_MS), cache))}


def opencv_rig(log: Path) -> dict[str, float]:
    """The rig as a solver that trusts the stamps finds it: each left frame paired with the
    right frame stamped nearest (as ``resync`` pairs them), both boards taken as one pose,
    :data:`OPENCV_PAIRS` of these pairs spread over the log, ``cv2.stereoCalibrate`` with
    both cameras' intrinsics fixed at the truth (so only the pairing costs the rig); its
    baseline's error (%) and rotation's error (degrees)."""
    from replay import open_reader
    from replay.records import Scenario
    from replay.topics import SCENARIO

    from .opencv_stereo_log import corners, frames

    with open_reader(log) as reader:
        (record,) = [Scenario.from_message(reader.decode(raw))
                     for raw in reader.raw_messages() if raw.topic == SCENARIO]
    (left_truth,) = [c for c in record.cameras if c.namespace == LEFT]
    (right_truth,) = [c for c in record.cameras if c.namespace == RIGHT]
    size = (7, 6)
    left = corners(frames(log, f"{LEFT}/image_raw"), size, window=OPENCV_WINDOW)
    right = corners(frames(log, f"{RIGHT}/image_raw"), size, window=OPENCV_WINDOW)
    right_ns = np.array([stamp for stamp, _ in right], dtype=np.int64)
    pairs = []
    for stamp, left_px in left:
        right_px = right[int(np.argmin(np.abs(right_ns - stamp)))][1]
        if left_px is not None and right_px is not None:
            # numbered from the end nearer the left view's first corner (a board turned
            # across the vertical is numbered from either end)
            flipped = right_px[::-1]
            if np.abs(flipped - left_px).sum() < np.abs(right_px - left_px).sum():
                right_px = flipped
            pairs.append((left_px.astype(np.float32), right_px.astype(np.float32)))
    pairs = pairs[::max(1, len(pairs) // OPENCV_PAIRS)]
    board = np.zeros((size[0] * size[1], 3), np.float32)
    board[:, :2] = np.mgrid[0:size[0], 0:size[1]].T.reshape(-1, 2) * float(BOARD[3])
    _rms, *_, rotation, translation, _e, _f = cv2.stereoCalibrate(
        [board] * len(pairs), [p[0] for p in pairs], [p[1] for p in pairs],
        left_truth.k, left_truth.d, right_truth.k, right_truth.d,
        (left_truth.width, left_truth.height), flags=cv2.CALIB_FIX_INTRINSIC)
    right_from_left = np.linalg.inv(right_truth.world_from_camera) @ left_truth.world_from_camera
    true_baseline = float(np.linalg.norm(right_from_left[:3, 3]))
    turn = rotation @ right_from_left[:3, :3].T
    angle = math.degrees(math.acos(min(1.0, max(-1.0, (float(np.trace(turn)) - 1) / 2))))
    return {"baseline_error_percent":
            abs(float(np.linalg.norm(translation)) / true_baseline - 1) * 100,
            "rotation_error_deg": angle, "joint_views": len(pairs)}


def _kept(path: Path) -> dict[str, dict[str, Any]]:
    """Results of an earlier run, by key (a line cut short is run again)."""
    out = {}
    if path.exists():
        for line in path.read_text().splitlines():
            with contextlib.suppress(ValueError):
                entry = json.loads(line)
                out[entry["key"]] = entry
    return out


def _results(keys: list[str], run: Any, keep: Path) -> Iterator[dict[str, Any]]:
    """Each key's result: kept from an earlier run, or run now and appended to ``keep``."""
    kept = _kept(keep)
    for key in keys:
        if key not in kept:
            kept[key] = run(key)
            keep.parent.mkdir(parents=True, exist_ok=True)
            cut = keep.exists() and not keep.read_bytes().endswith(b"\n") \
                and keep.stat().st_size > 0
            with keep.open("a") as f:  # a line cut short stays apart from the next one
                f.write(("\n" if cut else "") + json.dumps(kept[key]) + "\n")
            print(json.dumps(kept[key]), flush=True)
        yield kept[key]


def offset_table(kind: str, results: list[dict[str, Any]]) -> list[str]:
    """Per offset: logs measured (of logs), median and 95th percentile of |error|, the RMS
    of error / sigma and the median frames that carried it."""
    rows = []
    for offset in OFFSETS_MS:
        mine = [r for r in results if f"-o{offset:+g}-" in r["key"]]
        measured = [r for r in mine if "error_ms" in r]
        if not measured:
            rows.append([f"{offset:+g}", f"0 of {len(mine)}", "", "", "", ""])
            continue
        errors = np.abs([r["error_ms"] for r in measured])
        z = np.array([r["error_ms"] / r["std_ms"] for r in measured])
        rows.append([f"{offset:+g}", f"{len(measured)} of {len(mine)}",
                     f"{np.median(errors):.3f}", f"{np.percentile(errors, 95):.3f}",
                     f"{math.sqrt(float(np.mean(z ** 2))):.2f}",
                     f"{np.median([r['frames'] for r in measured]):.0f}"])
    header = ["offset (ms)", "logs measured", "median abs error (ms)", "p95 abs error (ms)",
              "RMS error/sigma", "moving frames (median)"]
    print(f"\n{kind}:")
    return markdown_table(header, rows)


def rig_table(results: list[dict[str, Any]]) -> list[str]:
    """Medians over the seeds of the rig's errors, calibrated each way (a way that gave no
    rig says why, in its row: the commonest reason)."""
    late = f"right camera {RIG_OFFSET_MS:g} ms late"
    rows = []
    for name, what in (("true", "camlog, true stamps"),
                       ("estimated", f"camlog, {late}: offset measured and views paired by it"),
                       ("stamps", f"camlog, {late}: paired by stamps (resync)"),
                       ("opencv_true", "OpenCV stereoCalibrate, true stamps"),
                       ("opencv_stamps", f"OpenCV stereoCalibrate, {late}: paired by stamps")):
        got = [r[name] for r in results if r.get(name, {}).get("joint_views")]
        if not got:
            reasons = [r[name]["why_not"] for r in results if "why_not" in r.get(name, {})]
            why = max(set(reasons), key=reasons.count).removeprefix("camlog calibrate: error: ") \
                if reasons else ""
            rows.append([what, f"0 of {len(results)}" + (f": {why}" if why else ""),
                         "", "", ""])
            continue
        rows.append([what, f"{len(got)} of {len(results)}",
                     f"{np.median([g['baseline_error_percent'] for g in got]):.3f}",
                     f"{np.median([g['rotation_error_deg'] for g in got]):.4f}",
                     f"{np.median([g['joint_views'] for g in got]):.0f}"])
    header = ["calibrated by", "rigs", "baseline error (%, median)",
              "rotation error (deg, median)", "joint views (median)"]
    return markdown_table(header, rows)


def natural_figure(results: list[dict[str, Any]], path: Path) -> None:
    """|error| of each natural-scene log against its features' speed across the rows
    (log-log), one colour per offset (an offset's ring drawn around the next one's: one
    seed's offsets often err alike), crossed at the floor where the log did not show it."""
    width, height, margin = 720, 420, 70
    img = np.full((height, width, 3), 255, np.uint8)
    measured = sorted((r for r in results if "error_ms" in r and r.get("row_speed_px_s")),
                      key=lambda r: OFFSETS_MS.index(case_of(r["key"]).offset_ms))
    unobserved = [row_speed_px_s(case_of(r["key"])) for r in results if "why_not" in r]
    colours = [(200, 90, 40), (40, 160, 40), (40, 40, 220), (160, 40, 160), (20, 140, 200)]
    grey = (120, 120, 120)
    xs = (1.0, 1000.0)  # px/s
    ys = (1e-4, 10.0)  # ms

    def to_px(speed: float, error: float) -> tuple[int, int]:
        u = (math.log10(speed) - math.log10(xs[0])) / (math.log10(xs[1]) - math.log10(xs[0]))
        v = (math.log10(max(error, ys[0])) - math.log10(ys[0])) \
            / (math.log10(ys[1]) - math.log10(ys[0]))
        return (int(margin + u * (width - 2 * margin)),
                int(height - margin - v * (height - 2 * margin)))

    def text(words: str, at: tuple[int, int], scale: float = 0.4) -> None:
        cv2.putText(img, words, at, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 1, cv2.LINE_AA)

    def dot(centre: tuple[int, int], index: int) -> None:
        cv2.circle(img, centre, 3 + 2 * (len(OFFSETS_MS) - 1 - index), colours[index], -1,
                   cv2.LINE_AA)

    cv2.rectangle(img, (margin, margin), (width - margin, height - margin), (0, 0, 0), 1)
    for decade in range(4):
        text(f"{10 ** decade:g}", (to_px(10.0 ** decade, 1.0)[0] - 10, height - margin + 18))
    for power in range(-4, 2):
        text(f"{10.0 ** power:g}", (8, to_px(1.0, 10.0 ** power)[1] + 4))
    for r in measured:
        dot(to_px(r["row_speed_px_s"], abs(r["error_ms"])),
            OFFSETS_MS.index(case_of(r["key"]).offset_ms))
    for speed in unobserved:
        x, y = to_px(max(speed, xs[0]), ys[0])
        cv2.drawMarker(img, (x, y - 6), grey, cv2.MARKER_TILTED_CROSS, 9, 1, cv2.LINE_AA)
    text("natural features: |offset error| (ms) against the rig's row speed (px/s)",
         (margin, 40), 0.5)
    for i, offset in enumerate(OFFSETS_MS):  # the legend, in the plot's upper left
        dot((margin + 16, margin + 18 + 22 * i), i)
        text(f"{offset:+g} ms late", (margin + 34, margin + 22 + 22 * i))
    legend_y = margin + 18 + 22 * len(OFFSETS_MS)
    cv2.drawMarker(img, (margin + 16, legend_y), grey, cv2.MARKER_TILTED_CROSS, 9, 1,
                   cv2.LINE_AA)
    text("not observable", (margin + 34, legend_y + 4))
    ok, png = cv2.imencode(".png", img)
    assert ok
    write_bytes_atomic(path, png.tobytes())
    print(f"wrote {path}", flush=True)


def run(*, seeds: int, cases: list[str], cache: Path, keep: Path, write_docs: bool) -> None:
    """The sweep: every case's logs, their tables (and figure), written into the docs."""
    tables: dict[str, list[str]] = {}
    for kind in ("board", "natural"):
        if kind not in cases:
            continue
        plan = {Case(kind, seed, offset).key: Case(kind, seed, offset)
                for seed in range(FIRST_SEED, FIRST_SEED + seeds) for offset in OFFSETS_MS}
        results = list(_results(list(plan), lambda key, p=plan: measure(p[key], cache), keep))
        tables[f"time_offset_{kind}"] = offset_table(kind, results)
        print("\n".join(tables[f"time_offset_{kind}"]))
        if kind == "natural" and write_docs:
            natural_figure(results, FIGURE)
    if "rig" in cases:
        rig_seeds = range(FIRST_SEED, FIRST_SEED + seeds)
        rigs = _results([f"rig-s{s}" for s in rig_seeds],
                        lambda key: calibrate_rig(int(key.split("-s")[1]), cache), keep)
        peers = _results([f"opencv-s{s}" for s in rig_seeds],
                         lambda key: opencv_rigs(int(key.split("-s")[1]), cache), keep)
        results = [{**camlog_rigs, **opencv, "key": camlog_rigs["key"]}
                   for camlog_rigs, opencv in zip(list(rigs), list(peers), strict=True)]
        tables["time_offset_rig"] = rig_table(results)
        print("\n".join(tables["time_offset_rig"]))
    if write_docs:
        for name, lines in tables.items():
            write_table(name, lines)


def main() -> None:
    """Parse the command line and run the sweep."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds per offset (default 20)")
    parser.add_argument("--cases", default="board,natural,rig",
                        help="comma-separated: board, natural, rig (default all)")
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                        help=f"recordings (default {DEFAULT_CACHE})")
    parser.add_argument("--keep", type=Path, default=DEFAULT_CACHE / "results.jsonl",
                        help="each log's result, one JSON line, read back by a later run")
    add_write_docs(parser)
    args = parser.parse_args()
    run(seeds=args.seeds, cases=args.cases.split(","), cache=args.cache, keep=args.keep,
        write_docs=args.write_docs)


if __name__ == "__main__":
    main()
