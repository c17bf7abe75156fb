"""``camlog process`` on recorded scenes, against the ground truth in the log."""

from __future__ import annotations

import hashlib
import tomllib
from pathlib import Path

import cv2
import numpy as np
import pytest

from camlog.cli import main
from replay import CameraInfo, CompressedImage, Image, PointStamped, PoseStamped, open_reader
from replay.calibration_yaml import save_calibration
from replay.camera import CameraModel
from replay.frames import decode_frame, decompress, encode_compressed
from replay.geometry import rotation_from_quat_xyzw
from replay.topics import PROCESSED
from tests.outputs import temp_outputs
from tests.slow import renders

LEFT = "/stereo_camera/left"
IMAGE = f"{LEFT}/image_raw"
SCENARIOS = Path(__file__).resolve().parents[3] / "datasets" / "scenarios"


def record(out: Path, scenario: str, *options: str) -> Path:
    assert main(["record", scenario, "-o", str(out), "--no-progress", *options]) == 0
    return out


def read(path: Path, *topics: str) -> dict[str, list[object]]:
    out: dict[str, list[object]] = {t: [] for t in topics}
    with open_reader(path) as reader:
        for rec in reader.messages(topics):
            out[rec.topic].append(rec.message)
    return out


def moving_block_spec(tmp: Path) -> Path:
    """red_block with the block at random untilted poses, a new one every 3 frames."""
    text = (SCENARIOS / "red_block.toml").read_text()
    head = text.partition("[targets.motion]")[0]
    spec = tmp / "moving_block.toml"
    spec.write_text(head + '[targets.motion]\nkind = "random_hold"\nhold_s = 0.1\n'
                    "center_m = [0.0, 0.01, 0.38]\nxy_range_m = 0.02\n"
                    "z_range_m = [0.36, 0.42]\nmax_tilt_rad = 0.0\n")
    assert tomllib.loads(spec.read_text())["targets"][0]["motion"]["kind"] == "random_hold"
    return spec


@pytest.fixture(scope="module")
@renders
def red_block(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The chapter's scene at the chapter's 640x480 (the centroid claim depends on it)."""
    return record(tmp_path_factory.mktemp("red") / "red_block.mcap", "red_block",
                  "--frames", "3")


@pytest.fixture(scope="module")
def processed(red_block: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("out") / "processed.mcap"
    assert main(["process", str(red_block), "--topic", IMAGE, "--red-pixels", "--edges",
                 "-o", str(out)]) == 0
    return out


def box_outline_px(pose: PoseStamped, info: CameraInfo, size_m: np.ndarray) -> np.ndarray:
    """Convex hull ``(N, 2)`` of the box's 8 corners projected with the true camera model."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    corners_in_target = signs * size_m / 2
    camera_from_target = rotation_from_quat_xyzw(pose.orientation_xyzw)
    corners = corners_in_target @ camera_from_target.T + pose.position_m
    uv = CameraModel.from_camera_info(info).project(corners)
    return cv2.convexHull(uv.astype(np.float32)).reshape(-1, 2).astype(np.float64)


def polygon_centroid(poly: np.ndarray) -> np.ndarray:
    x, y = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    area = cross.sum() / 2
    return np.array([((x + x1) * cross).sum(), ((y + y1) * cross).sum()]) / (6 * area)


def distance_to_outline(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    a, b = poly, np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("psk,sk->ps", points[:, None] - a, ab) / (ab**2).sum(1), 0, 1)
    nearest = a + t[..., None] * ab
    return np.linalg.norm(points[:, None] - nearest, axis=2).min(axis=1)


def test_red_block_centroid_is_the_image_centre(processed: Path, red_block: Path) -> None:
    out = read(processed, f"{LEFT}/red_centroid", f"{LEFT}/red_count",
               f"{LEFT}/output_video", IMAGE)
    centroids = out[f"{LEFT}/red_centroid"]
    assert len(centroids) == len(out[IMAGE]) == 3
    for centroid, count, video, image in zip(centroids, out[f"{LEFT}/red_count"],
                                             out[f"{LEFT}/output_video"], out[IMAGE],
                                             strict=True):
        assert isinstance(centroid, PointStamped) and isinstance(count, PointStamped)
        assert isinstance(video, Image) and isinstance(image, Image)
        assert abs(centroid.point[0] - 319.5) <= 0.5 and abs(centroid.point[1] - 239.5) <= 0.5
        assert centroid.stamp_ns == count.stamp_ns == video.stamp_ns == image.stamp_ns
        assert count.point[0] > 200 * 200  # a 2 cm block 9.5 cm away is ~218 px wide
        assert video.encoding == "rgb8" and tuple(video.pixels[240, 320]) == (0, 0, 255)


def test_input_is_kept_byte_for_byte_and_never_modified(red_block: Path, tmp_path: Path) -> None:
    before = hashlib.sha256(red_block.read_bytes()).hexdigest()
    out = tmp_path / "out.mcap"
    assert main(["process", str(red_block), "--topic", IMAGE, "--edges", "-o", str(out)]) == 0
    assert hashlib.sha256(red_block.read_bytes()).hexdigest() == before
    with open_reader(red_block) as src, open_reader(out) as dst:
        original = [(r.topic, r.log_time_ns, bytes(r.data)) for r in src.raw_messages()]
        copied = [(r.topic, r.log_time_ns, bytes(r.data)) for r in dst.raw_messages(src.topics)]
        assert copied == original
        assert set(dst.topics) == set(src.topics) | {f"{LEFT}/edges", PROCESSED}
    dropped = tmp_path / "only.mcap"
    assert main(["process", str(red_block), "--topic", IMAGE, "--edges", "--drop-input",
                 "-o", str(dropped)]) == 0
    with open_reader(dropped) as reader:
        assert set(reader.topics) == {f"{LEFT}/edges", PROCESSED}


def test_edges_lie_on_the_projected_block_outline(processed: Path) -> None:
    out = read(processed, f"{LEFT}/edges", f"{LEFT}/ground_truth/red_block",
               f"{LEFT}/camera_info")
    edges, pose, info = (out[t][0] for t in out)
    assert isinstance(edges, Image) and isinstance(pose, PoseStamped)
    assert isinstance(info, CameraInfo)
    outline = box_outline_px(pose, info, np.array([0.02, 0.02, 0.01]))
    rows, cols = np.nonzero(edges.pixels)
    distance = distance_to_outline(np.column_stack([cols, rows]).astype(np.float64), outline)
    assert len(distance) > 800
    assert np.mean(distance <= 1.5) >= 0.99
    # the outline is covered: every point along it has an edge pixel within 1.5 px
    to_edge = cv2.distanceTransform(np.where(edges.pixels > 0, 0, 255).astype(np.uint8),
                                    cv2.DIST_L2, 5)
    a, b = outline, np.roll(outline, -1, axis=0)
    samples = np.concatenate([a + t * (b - a) for t in np.linspace(0, 1, 200)[:, None, None]])
    u, v = np.rint(samples).astype(int).T
    assert np.all(to_edge[v, u] <= 1.5)


@pytest.mark.slow
def test_moving_block_centroid_follows_the_ground_truth(tmp_path: Path) -> None:
    log = record(tmp_path / "moving.mcap", str(moving_block_spec(tmp_path)),
                 "--frames", "24", "--resolution", "320x240")
    out = tmp_path / "out.mcap"
    assert main(["process", str(log), "--topic", IMAGE, "--red-pixels", "-o", str(out)]) == 0
    got = read(out, f"{LEFT}/red_centroid", f"{LEFT}/ground_truth/red_block",
               f"{LEFT}/camera_info")
    info = got[f"{LEFT}/camera_info"][0]
    assert isinstance(info, CameraInfo)
    truth = {p.stamp_ns: p for p in got[f"{LEFT}/ground_truth/red_block"]
             if isinstance(p, PoseStamped)}
    centroids = got[f"{LEFT}/red_centroid"]
    assert len(centroids) == len(truth) == 24
    positions = set()
    for centroid in centroids:
        assert isinstance(centroid, PointStamped)
        pose = truth[centroid.stamp_ns]
        positions.add(tuple(np.round(pose.position_m, 6)))
        # The red area is the box's silhouette: the hull of its projected corners. Its
        # centroid is not the projected box centre: the top face is 5 mm nearer than the
        # centre, so perspective pushes it outwards by up to ~6 px at 640x480 here.
        silhouette = polygon_centroid(box_outline_px(pose, info, np.array([0.02, 0.02, 0.01])))
        assert np.linalg.norm(centroid.point[:2] - silhouette) <= 0.1
        centre = CameraModel.from_camera_info(info).project(pose.position_m[None])[0]
        top = pose.position_m - rotation_from_quat_xyzw(pose.orientation_xyzw)[:, 2] * 0.005
        top_centre = CameraModel.from_camera_info(info).project(top[None])[0]
        assert np.linalg.norm(centroid.point[:2] - centre) <= np.linalg.norm(
            top_centre - centre) + 0.5
    assert len(positions) >= 6  # the block really moved


@pytest.mark.slow
def test_every_third_frame_and_rate_limit(tmp_path: Path) -> None:
    log = record(tmp_path / "red.mcap", "red_block", "--frames", "10", "--resolution",
                 "320x240")
    stamps = [m.stamp_ns for m in read(log, IMAGE)[IMAGE] if isinstance(m, Image)]
    for flag, kept in ((["--every", "3"], [0, 3, 6, 9]), (["--rate", "10"], [0, 3, 6, 9]),
                       (["--rate", "7"], [0, 5])):
        out = tmp_path / f"every{flag[1]}.mcap"
        assert main(["process", str(log), "--topic", IMAGE, "--red-pixels", *flag,
                     "-o", str(out)]) == 0
        got = read(out, f"{LEFT}/red_count")[f"{LEFT}/red_count"]
        assert [m.stamp_ns for m in got if isinstance(m, PointStamped)] == [
            stamps[i] for i in kept]


def test_compressed_input_and_output(red_block: Path, tmp_path: Path) -> None:
    from replay import open_writer

    log = tmp_path / "compressed.mcap"
    with open_writer(log) as writer:
        for image in read(red_block, IMAGE)[IMAGE]:
            assert isinstance(image, Image)
            writer.write(f"{IMAGE}/compressed", encode_compressed(decode_frame(image), "png"))
    out = tmp_path / "out.mcap"
    assert main(["process", str(log), "--topic", f"{IMAGE}/compressed", "--red-pixels",
                 "--edges", "--compress", "png", "-o", str(out)]) == 0
    got = read(out, f"{LEFT}/output_video/compressed",
               f"{LEFT}/edges/compressed", f"{LEFT}/red_centroid")
    reference = read(_processed_again(red_block, tmp_path), f"{LEFT}/output_video",
                     f"{LEFT}/edges")
    for name in ("output_video", "edges"):
        mine = got[f"{LEFT}/{name}/compressed"]
        theirs = reference[f"{LEFT}/{name}"]
        assert len(mine) == len(theirs) == 3
        for compressed, image in zip(mine, theirs, strict=True):
            assert isinstance(compressed, CompressedImage) and "png" in compressed.format
            assert decompress(compressed, decode_frame(compressed)) == image  # png is lossless
    assert len(got[f"{LEFT}/red_centroid"]) == 3


def _processed_again(red_block: Path, tmp_path: Path) -> Path:
    out = tmp_path / "plain.mcap"
    assert main(["process", str(red_block), "--topic", IMAGE, "--red-pixels", "--edges",
                 "--drop-input", "-o", str(out)]) == 0
    return out


def test_rectify_with_a_calibration_file(red_block: Path, tmp_path: Path) -> None:
    from processors.rectify import Rectifier

    info = read(red_block, f"{LEFT}/camera_info")[f"{LEFT}/camera_info"][0]
    assert isinstance(info, CameraInfo)
    k = info.k.copy()
    k[0, 0] *= 0.9  # a calibration that differs from the truth, so the output must change
    calibrated = CameraInfo(0, "", info.width, info.height, "plumb_bob",
                            np.array([-0.2, 0.05, 0, 0, 0]), k, np.eye(3),
                            np.hstack([info.k, np.zeros((3, 1))]))
    yaml = tmp_path / "ost.yaml"
    save_calibration(yaml, calibrated, camera_name="left")
    out = tmp_path / "rect.mcap"
    assert main(["process", str(red_block), "--topic", IMAGE, "--rectify", str(yaml),
                 "-o", str(out)]) == 0
    got = read(out, f"{LEFT}/image_rect", IMAGE)
    rectifier = Rectifier(camera_info=calibrated)
    for rect, image in zip(got[f"{LEFT}/image_rect"], got[IMAGE], strict=True):
        assert isinstance(rect, Image) and isinstance(image, Image)
        (_, expected), = rectifier(decode_frame(image))
        assert rect == expected and not np.array_equal(rect.pixels, image.pixels)


# --- bad input: one line on stderr, exit 1, no output left behind -------------------------

def assert_failed_cleanly(
    capsys: pytest.CaptureFixture[str], out: Path, code: int, *needles: str
) -> str:
    err = capsys.readouterr().err
    assert code == 1
    assert err.count("\n") == 1 and err.startswith("camlog process: error: ")
    for needle in needles:
        assert needle in err
    assert not out.exists() and temp_outputs(out.parent) == []
    return err


def test_missing_topic_lists_the_topics(
    red_block: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out.mcap"
    code = main(["process", str(red_block), "--topic", "/nope/image_raw", "--edges",
                 "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "/nope/image_raw", IMAGE, f"{LEFT}/camera_info")


def test_non_image_topic(red_block: Path, tmp_path: Path,
                         capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out.mcap"
    code = main(["process", str(red_block), "--topic", f"{LEFT}/camera_info", "--edges",
                 "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "CameraInfo")


def test_unsupported_encoding(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from replay import RawMessage, open_writer
    from replay.wire import ros2_typestore

    types = ros2_typestore().types
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="cam")
    msg = types["sensor_msgs/msg/Image"](header=header, height=2, width=2, encoding="yuv411",
                                         is_bigendian=0, step=4, data=np.zeros(8, np.uint8))
    data = bytes(ros2_typestore().serialize_cdr(msg, "sensor_msgs/msg/Image"))
    log = tmp_path / "yuv.mcap"
    with open_writer(log) as writer:
        writer.write_raw(RawMessage("/cam/image_raw", "sensor_msgs/msg/Image", 1, data, "cdr"))
    out = tmp_path / "out.mcap"
    code = main(["process", str(log), "--topic", "/cam/image_raw", "--edges", "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "yuv411", "/cam/image_raw", str(log))


def test_empty_log(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from replay import open_writer

    log = tmp_path / "empty.mcap"
    open_writer(log).close()
    out = tmp_path / "out.mcap"
    code = main(["process", str(log), "--topic", IMAGE, "--edges", "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "empty")


def test_a_bad_frame_mid_stream_leaves_nothing(
    red_block: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from replay import open_writer

    log = tmp_path / "sizes.mcap"
    with open_writer(log) as writer:
        for i, size in enumerate([(24, 32), (24, 32), (20, 32)]):
            writer.write("/cam/image_raw", Image(i, "cam", "mono8", np.zeros(size, np.uint8)))
    k = np.array([[30.0, 0, 15.5], [0, 30.0, 11.5], [0, 0, 1]])
    yaml = tmp_path / "ost.yaml"
    save_calibration(yaml, CameraInfo(0, "", 32, 24, "plumb_bob", np.zeros(5), k),
                     camera_name="cam")
    out = tmp_path / "out.mcap"
    code = main(["process", str(log), "--topic", "/cam/image_raw", "--rectify", str(yaml),
                 "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "frame stamped 2", "32x20")


def test_no_processor_chosen(red_block: Path, tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out.mcap"
    code = main(["process", str(red_block), "--topic", IMAGE, "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, "--red-pixels")


def test_refuses_to_overwrite_the_input_or_mix_outputs(
    red_block: Path, processed: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = red_block.read_bytes()
    code = main(["process", str(red_block), "--topic", IMAGE, "--edges", "--overwrite",
                 "-o", str(red_block)])
    assert code == 1 and "is the input" in capsys.readouterr().err
    assert red_block.read_bytes() == before
    out = tmp_path / "twice.mcap"
    code = main(["process", str(processed), "--topic", IMAGE, "--edges", "-o", str(out)])
    assert_failed_cleanly(capsys, out, code, f"already has {LEFT}/edges",
                          "output namespace")
