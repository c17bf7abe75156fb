"""``camlog process`` output topics, the record of outputs, and option errors.

Outputs go to ``{input namespace}/{output}`` (or a chosen namespace), so both cameras of a
rig fit in one log; the log records which processor wrote each topic and how ``view`` shows
it, read back here with independent readers (mcap_ros2, rosbags) and through ``view``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from camlog.cli import main
from processors.registry import make_processor
from replay import Image, open_reader
from replay.frames import decode_frame
from replay.topics import PROCESSED
from rerun_export import view_logs
from tests.rrd import load_rrd

LEFT, RIGHT = "/stereo_camera/left", "/stereo_camera/right"
BOTH = ["--topic", f"{LEFT}/image_raw", "--topic", f"{RIGHT}/image_raw"]


def decoded(path: Path) -> dict[str, list[object]]:
    """Every message of an MCAP file decoded by the mcap_ros2 library, per topic."""
    out: dict[str, list[object]] = {}
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, message in reader.iter_decoded_messages():
            out.setdefault(channel.topic, []).append(message)
    return out


def test_both_cameras_into_one_log(red_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "both.mcap"
    assert main(["process", str(red_log), *BOTH, "--edges", "--red-pixels",
                 "-o", str(out)]) == 0
    got = decoded(out)
    for ns in (LEFT, RIGHT):
        assert len(got[f"{ns}/edges"]) == len(got[f"{ns}/image_raw"]) == 20
        assert len(got[f"{ns}/red_count"]) == 20
    # each camera's outputs are computed from its own images
    with open_reader(red_log) as reader:
        images = {r.topic: r.message for r in reader.messages([f"{LEFT}/image_raw",
                                                               f"{RIGHT}/image_raw"])}
    edges = make_processor("edges")
    for ns in (LEFT, RIGHT):
        image = images[f"{ns}/image_raw"]
        assert isinstance(image, Image)
        ((_, expected),) = edges(decode_frame(image))
        assert isinstance(expected, Image)
        last = got[f"{ns}/edges"][-1]
        np.testing.assert_array_equal(np.frombuffer(bytes(last.data), np.uint8)  # type: ignore[attr-defined]
                                      .reshape(expected.pixels.shape), expected.pixels)
    (record,) = got[PROCESSED]
    outputs = json.loads(record.data)["outputs"]  # type: ignore[attr-defined]
    assert {(o["topic"], o["source"], o["processor"], o["display"]) for o in outputs} == {
        (f"{ns}/{name}", f"{ns}/image_raw", processor, display) for ns in (LEFT, RIGHT)
        for processor, name, display in (("red_pixels", "output_video", "mask"),
                                         ("red_pixels", "red_centroid", "point_2d"),
                                         ("red_pixels", "red_count", "scalar"),
                                         ("edges", "edges", "edges"))}
    rec = load_rrd(view_logs([out], output=tmp_path / "both.rrd", progress=False).output
                   or tmp_path / "missing.rrd")
    for camera in ("/world/stereo_camera/left", "/world/stereo_camera/right"):
        assert rec.count(f"{camera}/edges", "SegmentationImage:buffer") == 20
        assert rec.count(f"{camera}/red_pixels/mask", "SegmentationImage:buffer") == 20


@pytest.mark.parametrize(("output_ns", "topics", "expected"), [
    ("/image_converter", [f"{LEFT}/image_raw"], ["/image_converter/edges"]),
    ("/proc{ns}", [f"{LEFT}/image_raw", f"{RIGHT}/image_raw"],
     [f"/proc{LEFT}/edges", f"/proc{RIGHT}/edges"]),
    ("/flat/", [f"{RIGHT}/image_raw"], ["/flat/edges"]),
])
def test_output_namespace(red_log: Path, tmp_path: Path, output_ns: str, topics: list[str],
                          expected: list[str]) -> None:
    out = tmp_path / "ns.mcap"
    args = [a for t in topics for a in ("--topic", t)]
    assert main(["process", str(red_log), *args, "--edges", "--output-ns", output_ns,
                 "--drop-input", "-o", str(out)]) == 0
    with open_reader(out) as reader:
        assert sorted(reader.topics) == sorted([*expected, PROCESSED])


def run_failing(capsys: pytest.CaptureFixture[str], out: Path, *argv: str) -> str:
    code = main(["process", *argv, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and err.startswith("camlog process: error: ")
    assert not out.exists()
    return err


@pytest.mark.parametrize(("flags", "needle"), [
    (["--edges", "--low", "-1"], "--low: must be >= 0, got -1.0"),
    (["--edges", "--low", "abc"], "--low: expected a finite number, got 'abc'"),
    (["--edges", "--low", "200", "--high", "100"], "--low, --high: Canny thresholds need"),
    (["--red-pixels", "--ratio", "2.5"], "--ratio: expected an integer, got '2.5'"),
    (["--ratio", "3", "--edges"], "--ratio needs --red-pixels"),
    (["--edges", "--every", "0"], "--every: must be >= 1, got 0"),
    (["--edges", "--rate", "-2"], "--rate: must be > 0, got -2.0"),
    (["--every", "2"], "choose at least one of --red-pixels, --edges, --rectify"),
    (["--edges", "--output-ns", "{ns}/x"], "must start with '/'"),
    (["--edges", "--output-ns", "/image_converter", *BOTH],
     "/image_converter/edges would hold both"),
])
def test_option_errors_name_the_flags(red_log: Path, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str], flags: list[str],
                                      needle: str) -> None:
    topic = [] if "--topic" in flags else ["--topic", f"{LEFT}/image_raw"]
    err = run_failing(capsys, tmp_path / "out.mcap", str(red_log), *topic, *flags)
    assert needle in err


def test_a_calibration_belongs_to_one_camera(red_log: Path, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    from replay.calibration_yaml import save_calibration

    with open_reader(red_log) as reader:
        info = next(iter(reader.messages([f"{LEFT}/camera_info"]))).message
    yaml = tmp_path / "left.yaml"
    save_calibration(yaml, info, camera_name="left")  # type: ignore[arg-type]
    err = run_failing(capsys, tmp_path / "out.mcap", str(red_log), *BOTH, "--rectify",
                      str(yaml))
    assert "rectify takes one camera's calibration" in err
    missing = run_failing(capsys, tmp_path / "out.mcap", str(red_log), "--topic",
                          f"{LEFT}/image_raw", "--rectify", str(tmp_path / "none.yaml"))
    assert "none.yaml" in missing


def test_the_record_survives_convert_and_tells_view_how_to_draw(
        red_log: Path, tmp_path: Path) -> None:
    processed = tmp_path / "odd_names.mcap"
    assert main(["process", str(red_log), "--topic", f"{LEFT}/image_raw", "--edges",
                 "--red-pixels", "--output-ns", "/analysis/cam_a", "-o", str(processed)]) == 0
    bag = tmp_path / "odd_names.bag"
    assert main(["convert", str(processed), str(bag), "--no-progress"]) == 0
    with AnyReader([bag]) as reader:
        (connection,) = [c for c in reader.connections if c.topic == PROCESSED]
        ((_, _, raw),) = list(reader.messages(connections=[connection]))
        text = reader.deserialize(raw, connection.msgtype).data
    assert {o["topic"] for o in json.loads(text)["outputs"]} >= {"/analysis/cam_a/edges"}
    rec = load_rrd(view_logs([bag], output=tmp_path / "bag.rrd", progress=False).output
                   or tmp_path / "missing.rrd")
    # names the view could not guess: drawn on the source camera because of the record
    camera = "/world/stereo_camera/left"
    assert rec.count(f"{camera}/edges", "SegmentationImage:buffer") == 20
    assert rec.count(f"{camera}/red_pixels/centroid", "Points2D:positions") == 20
    assert rec.count("/metrics/red_pixel_count/stereo_camera/left", "Scalars:scalars") == 20


def test_logs_without_a_record_keep_routing_by_name(red_log: Path, tmp_path: Path) -> None:
    processed = tmp_path / "chapter.mcap"
    assert main(["process", str(red_log), "--topic", f"{LEFT}/image_raw", "--edges",
                 "--red-pixels", "--output-ns", "/image_converter", "-o", str(processed)]) == 0
    legacy = tmp_path / "legacy.mcap"
    assert main(["convert", str(processed), str(legacy), "--no-progress", "--topics",
                 "/stereo_camera/*", "/image_converter/*", "/camlog/scenario"]) == 0
    with open_reader(legacy) as reader:
        assert PROCESSED not in reader.topics
    rec = load_rrd(view_logs([legacy], output=tmp_path / "legacy.rrd", progress=False).output
                   or tmp_path / "missing.rrd")
    camera = "/world/stereo_camera/left"
    assert rec.count(f"{camera}/edges", "SegmentationImage:buffer") == 20
    assert rec.count(f"{camera}/red_pixels/mask", "SegmentationImage:buffer") == 20
