"""camera_info -> ``camlog view`` -> .rrd -> ``camlog export --calibration`` -> YAML keeps
every number bit for bit, for every lens model and for a Foxglove ``kannala_brandt`` model;
the .rrd's ``CameraInfo`` read with rerun's own dataframe API holds the same numbers."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pyarrow as pa
import pytest
from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
from google.protobuf.timestamp_pb2 import Timestamp
from mcap_protobuf.writer import Writer as ProtobufWriter
from rerun.chunk import RrdReader
from ruamel.yaml import YAML

from camlog.cli import main
from replay import CameraInfo, Image, Text, open_writer

T0 = 1_700_000_000_000_000_000
WIDTH, HEIGHT = 64, 48
#: numbers whose every bit matters
K = np.array([[61.23456789012345, 0.0, 31.987654321098765],
              [0.0, 61.98765432109876, 23.456789012345678], [0.0, 0.0, 1.0]])
R = cv2.Rodrigues(np.array([0.0123456789, -0.0234567891, 0.00345678912]))[0]
P = np.array([[59.87654321098765, 0.0, 30.123456789012345, -1.2345678901234567],
              [0.0, 59.87654321098765, 22.987654321098765, 0.0], [0.0, 0.0, 1.0, 0.0]])
D = {"plumb_bob": [-0.2718281828459045, 0.14142135623730951, 1.2345678901234567e-05,
                   -9.876543210987654e-06, -0.031415926535897934],
     "rational_polynomial": [-0.3183098861837907, 0.1102230246251565, 0.0004, -0.0003,
                             -0.018, 0.02000000000000001, 0.01, -0.0040000000000000036],
     "equidistant": [-0.04000000000000001, 0.0012345678901234567, -0.0008, 1e-4 / 3]}


def _log(path: Path, model: str) -> Path:
    with open_writer(path) as writer:
        for i in range(3):
            stamp = T0 + i * 100_000_000
            pixels = np.full((HEIGHT, WIDTH, 3), 40 * i, np.uint8)
            writer.write("/cam/image_raw", Image(stamp, "cam_optical", "rgb8", pixels),
                         log_time_ns=stamp)
            writer.write("/cam/camera_info", CameraInfo(
                stamp, "cam_optical", WIDTH, HEIGHT, model, np.array(D[model]), K, R, P),
                log_time_ns=stamp)
    return path


def _read_yaml(path: Path) -> dict[str, object]:
    loaded = YAML(typ="safe").load(path.read_text())
    assert isinstance(loaded, dict)
    return loaded


def _export(log: Path, tmp_path: Path) -> tuple[Path, Path]:
    rrd, folder = tmp_path / "rec.rrd", tmp_path / "cal"
    assert main(["view", str(log), "-o", str(rrd), "--no-progress"]) == 0
    assert main(["export", str(rrd), "--calibration", "-o", str(folder)]) == 0
    return rrd, folder


def _rrd_camera_info(rrd: Path, entity: str) -> dict[str, list[object]]:
    """The CameraInfo components at ``entity``, read with rerun's dataframe API."""
    reader = RrdReader(rrd)
    (entry,) = reader.recordings()
    store = reader.stream(store=entry).collect()
    table = store.reader(index="log_time", contents=entity).to_arrow_table()
    out = {}
    for name in table.column_names:
        if f"{entity}:CameraInfo:" in name:
            rows = table.filter(pa.compute.is_valid(table.column(name)))
            out[name.rpartition(":")[2]] = rows.column(name).to_pylist()[-1]
    return out


@pytest.mark.parametrize("model", list(D))
def test_every_number_comes_back(model: str, tmp_path: Path,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    rrd, folder = _export(_log(tmp_path / "cam.mcap", model), tmp_path)
    out = capsys.readouterr().out
    assert f"/world/cam: {folder / 'cam.yaml'}" in out
    assert "wrote 1 calibration files" in out
    assert sorted(p.name for p in folder.iterdir()) == ["cam.yaml"]
    read = _read_yaml(folder / "cam.yaml")
    assert (read["image_width"], read["image_height"]) == (WIDTH, HEIGHT)
    assert (read["camera_name"], read["distortion_model"]) == ("cam", model)
    blocks = {"camera_matrix": K, "distortion_coefficients": np.array(D[model]),
              "rectification_matrix": R, "projection_matrix": P}
    for key, expected in blocks.items():
        block = read[key]
        assert isinstance(block, dict)
        assert block["data"] == expected.reshape(-1).tolist(), key  # exact floats
    # rerun's own reader sees the same float64 numbers beside the Pinhole
    stored = _rrd_camera_info(rrd, "/world/cam")
    assert stored["distortion_model"] == [model] and stored["frame_id"] == ["cam_optical"]
    assert stored["width"] == [WIDTH] and stored["height"] == [HEIGHT]
    assert stored["k"] == K.reshape(-1).tolist() and stored["d"] == D[model]
    assert stored["r"] == R.reshape(-1).tolist() and stored["p"] == P.reshape(-1).tolist()


def _stamp(stamp_ns: int) -> Timestamp:
    return Timestamp(seconds=stamp_ns // 10**9, nanos=stamp_ns % 10**9)


def test_a_foxglove_kannala_brandt_model_comes_back_as_equidistant(tmp_path: Path) -> None:
    """Foxglove's CameraCalibration (protobuf, written with Foxglove's own schema classes)
    names the fisheye model kannala_brandt: the same k1..k4 as ROS's equidistant."""
    log = tmp_path / "fox.mcap"
    d = D["equidistant"]
    with log.open("wb") as f:
        writer = ProtobufWriter(f)
        for i in range(3):
            t = T0 + i * 100_000_000
            writer.write_message("/fox/image", RawImage(
                timestamp=_stamp(t), frame_id="fox", width=WIDTH, height=HEIGHT,
                encoding="rgb8", step=WIDTH * 3,
                data=np.full((HEIGHT, WIDTH, 3), 50 * i, np.uint8).tobytes()),
                log_time=t, publish_time=t)
            writer.write_message("/fox/calibration", CameraCalibration(
                timestamp=_stamp(t), frame_id="fox", width=WIDTH, height=HEIGHT,
                distortion_model="kannala_brandt", D=d, K=K.reshape(-1).tolist(),
                R=R.reshape(-1).tolist(), P=P.reshape(-1).tolist()), log_time=t,
                publish_time=t)
        writer.finish()
    rrd, folder = _export(log, tmp_path)
    read = _read_yaml(folder / "fox.yaml")
    assert read["distortion_model"] == "equidistant"
    for key, expected in (("camera_matrix", K), ("distortion_coefficients", np.array(d)),
                          ("rectification_matrix", R), ("projection_matrix", P)):
        block = read[key]
        assert isinstance(block, dict) and block["data"] == expected.reshape(-1).tolist(), key
    stored = _rrd_camera_info(rrd, "/world/fox")
    assert stored["distortion_model"] == ["kannala_brandt"] and stored["d"] == d
    # the fisheye was shown through pinhole views (a rectified one: R is not the identity)
    reader = RrdReader(rrd)
    (entry,) = reader.recordings()
    table = reader.stream(store=entry).collect().reader(
        index="log_time", contents="/world/fox/rectified/image").to_arrow_table()
    assert table.num_rows == 3


def test_the_export_refuses_what_is_not_a_recording_of_cameras(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = _log(tmp_path / "cam.mcap", "plumb_bob")
    assert main(["export", str(log), "--calibration", "-o", str(tmp_path / "a")]) != 0
    assert "reads a rerun recording (.rrd)" in capsys.readouterr().err
    assert main(["export", str(log), "-o", str(tmp_path / "a")]) != 0
    err = capsys.readouterr().err
    assert "--topic" in err and "--calibration" in err
    fake = tmp_path / "fake.rrd"
    fake.write_bytes(b"not a recording")
    assert main(["export", str(fake), "--calibration", "-o", str(tmp_path / "b")]) != 0
    err = capsys.readouterr().err
    assert "cannot read" in err and "Traceback" not in err
    notes = tmp_path / "notes.mcap"
    with open_writer(notes) as writer:
        writer.write("/notes", Text("no camera here"), log_time_ns=T0)
    assert main(["view", str(notes), "-o", str(tmp_path / "notes.rrd"), "--no-progress"]) == 0
    assert main(["export", str(tmp_path / "notes.rrd"), "--calibration", "-o",
                 str(tmp_path / "c")]) != 0
    assert "holds no camera model" in capsys.readouterr().err
    assert not any((tmp_path / name).exists() for name in "abc")
