"""``view_logs`` on logs made by camlog's own commands, read back with rerun's loader."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from replay import CameraInfo, Image, PointStamped, Text, open_reader, open_writer
from replay.camera import CameraModel
from replay.frames import Color, Frame, encode_compressed
from rerun_export import LoggerOptions, view_logs
from rerun_export.overlays import CENTROID_MARKER, MASK_PIXEL
from tests.rrd import load_rrd, rerun_cli

LEFT, RIGHT = "/world/stereo_camera/left", "/world/stereo_camera/right"
SOURCE = "/stereo_camera/left"  # the processed camera's namespace in the log
PINHOLE = "Pinhole:image_from_camera"


def messages(path: Path, topic: str) -> list[object]:
    with open_reader(path) as reader:
        return [record.message for record in reader.messages([topic])]


@pytest.fixture(scope="module")
def processed_rrd(red_processed_log: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("view") / "processed.rrd"
    result = view_logs([red_processed_log], output=out, progress=False)
    assert result.output == out and result.warnings == []
    return out


def test_cameras_carry_their_pinhole_images_and_rig(processed_rrd: Path,
                                                    red_processed_log: Path) -> None:
    rec = load_rrd(processed_rrd)
    assert rec.entities_with(PINHOLE) == [LEFT, RIGHT]
    assert rec.blueprints == 1
    (info, *_) = messages(red_processed_log, "/stereo_camera/left/camera_info")
    assert isinstance(info, CameraInfo)
    (k_column_major,) = rec.column(LEFT, PINHOLE)
    np.testing.assert_allclose(np.reshape(k_column_major, (3, 3)).T, info.k, rtol=1e-6)
    assert rec.column(LEFT, "Pinhole:resolution") == [[[320.0, 240.0]]]
    for camera in (LEFT, RIGHT):
        assert rec.count(f"{camera}/image", "Image:buffer") == 20
        assert rec.timelines[f"{camera}/image"] == {"log_time", "header_stamp"}
        assert "Transform3D:translation" in rec.static[camera]
    # the right camera sits 0.02 m along the left camera's x axis (scenario world poses)
    (left_t,), (right_t,) = (rec.column(c, "Transform3D:translation") for c in (LEFT, RIGHT))
    (left_r,) = rec.column(LEFT, "Transform3D:mat3x3")
    x_axis = np.reshape(left_r, (3, 3)).T[:, 0]
    np.testing.assert_allclose(np.subtract(right_t, left_t).ravel(), 0.02 * x_axis, atol=1e-6)
    assert rec.timelines["/text/camlog/scenario"] == {"log_time"}


def test_processor_outputs_are_drawn_on_their_camera(processed_rrd: Path,
                                                     red_processed_log: Path) -> None:
    rec = load_rrd(processed_rrd)
    assert rec.count(f"{LEFT}/red_pixels/mask", "SegmentationImage:buffer") == 20
    assert rec.count(f"{LEFT}/edges", "SegmentationImage:buffer") == 20
    assert rec.count(f"{RIGHT}/edges", "SegmentationImage:buffer") == 0
    # outputs on every frame replace each other: nothing needs clearing
    assert rec.count(f"{LEFT}/red_pixels/mask", "Clear:is_recursive") == 0
    centroids = [m.point[:2].tolist() for m in messages(red_processed_log,
                                                         f"{SOURCE}/red_centroid")
                 if isinstance(m, PointStamped)]
    assert len(centroids) == 20
    logged = [row[0] for row in rec.column(f"{LEFT}/red_pixels/centroid", "Points2D:positions")]
    np.testing.assert_allclose(logged, centroids, atol=1e-4)
    counts = [m.point[0] for m in messages(red_processed_log, f"{SOURCE}/red_count")
              if isinstance(m, PointStamped)]
    scalars = rec.column("/metrics/red_pixel_count/stereo_camera/left", "Scalars:scalars")
    assert [row[0] for row in scalars] == counts and counts[0] > 0
    # the block's 8 corners, projected with the true camera, on every frame of both cameras
    # (the right camera sees the block at its edge: only the corners inside its image)
    for camera, visible in ((LEFT, [8]), (RIGHT, [1, 2, 3, 4, 5, 6, 7])):
        truth = rec.column(f"{camera}/ground_truth/red_block", "Points2D:positions")
        assert len(truth) == 20 and all(len(row) in visible for row in truth)
        assert all(-0.5 <= u <= 319.5 and -0.5 <= v <= 239.5 for row in truth for u, v in row)
    corners = np.array(rec.column(f"{LEFT}/ground_truth/red_block", "Points2D:positions")[0])
    np.testing.assert_allclose(corners.mean(axis=0), centroids[0], atol=1.0)


def test_mask_classes_survive_in_the_recording(red_processed_log: Path, tmp_path: Path) -> None:
    from rerun.chunk import RrdReader

    out = tmp_path / "mask.rrd"
    view_logs([red_processed_log], output=out,
              topics=[f"{SOURCE}/output_video"], end_s=0.01, progress=False)
    (store,) = RrdReader(out).recordings()
    buffers = [chunk.to_record_batch().column("SegmentationImage:buffer").to_pylist()
               for chunk in RrdReader(out).stream(store=store)
               if chunk.entity_path.endswith("/red_pixels/mask")]
    (classes,) = [np.array(b) for rows in buffers for b in rows if b is not None]
    assert set(np.unique(classes)) == {0, MASK_PIXEL, CENTROID_MARKER}
    # with no camera images in the selection, the outputs still go to their source camera
    assert f"{LEFT}/red_pixels/mask" in [c.entity_path for c in RrdReader(out).stream(store=store)]


@pytest.mark.slow
def test_calibration_corners_residuals_and_errors(mono_calibration_log: Path,
                                                  tmp_path: Path) -> None:
    out = tmp_path / "calibration.rrd"
    view_logs([mono_calibration_log], output=out, progress=False,
              options=LoggerOptions(residual_scale=10.0))
    rec = load_rrd(out)
    # the calibrated model (k1, k2) draws the camera: its raw image and overlays in a 2D
    # space of their own, an undistorted view under the camera
    cam, raw = "/world/simple_camera", "/raw/simple_camera"
    views = [json.loads(m.data) for m in messages(mono_calibration_log,
                                                  "/simple_camera/calibration/residuals")
             if isinstance(m, Text)]
    assert len(views) > 20
    corners = rec.column(f"{raw}/calibration/corners", "Points2D:positions")
    assert [len(row) for row in corners] == [42] * len(views)
    np.testing.assert_allclose(corners[0], views[0]["corners_px"], atol=1e-3)
    arrows = rec.column(f"{raw}/calibration/residuals", "Arrows2D:vectors")
    np.testing.assert_allclose(arrows[0], np.multiply(views[0]["residuals_px"], 10.0), atol=1e-4)
    errors = rec.column("/metrics/calibration_view_rms_px/simple_camera", "Scalars:scalars")
    np.testing.assert_allclose([e[0] for e in errors], [v["rms_px"] for v in views])
    labels = rec.column(f"{raw}/calibration/status", "Boxes2D:labels")
    assert labels[0][0].startswith(f"used: view RMS {views[0]['rms_px']:.3f} px")
    detections = len(messages(mono_calibration_log, "/simple_camera/calibration/detections"))
    assert rec.count(f"{raw}/calibration/detections", "Image:buffer") == detections
    # corners of a used view are cleared when the board moves: they never linger
    assert rec.count(f"{raw}/calibration/corners", "Clear:is_recursive") >= len(views) - 1
    assert rec.entities_with(PINHOLE) == [f"{cam}/undistorted"]
    # a view image per raw image that does not repeat the last (a held pose's frames do)
    pixels = [m.pixels.tobytes() for m in messages(mono_calibration_log,
                                                    "/simple_camera/image_raw")
              if isinstance(m, Image)]
    changes = sum(i == 0 or a != pixels[i - 1] for i, a in enumerate(pixels))
    assert rec.count(f"{raw}/image", "Image:buffer") == len(pixels) == 120
    assert 20 < rec.count(f"{cam}/undistorted/image", "Image:buffer") == changes < 120
    # the board at its solved poses, in 3D: the calibrated model images its corners where
    # the residuals say (corners minus residuals)
    board = rec.column(f"{cam}/calibration/board", "Points3D:positions")
    assert [len(row) for row in board] == [42] * len(views)
    (info,) = [m for m in messages(mono_calibration_log, "/simple_camera/calibrated/camera_info")
               if isinstance(m, CameraInfo)][:1]
    model = CameraModel.from_camera_info(info)
    np.testing.assert_allclose(
        model.project(np.asarray(views[0]["corners_in_camera_m"])),
        np.subtract(views[0]["corners_px"], views[0]["residuals_px"]), atol=2e-4)
    np.testing.assert_allclose(board[0], views[0]["corners_in_camera_m"], atol=1e-6)
    # the uncertainty map over the undistorted view, for the whole recording
    uncertainty = f"{cam}/undistorted/uncertainty"
    assert rec.count(uncertainty, "Image:buffer") == 1 and uncertainty in rec.static
    (label,) = rec.column(f"{uncertainty}/scale", "Boxes2D:labels")
    assert label[0].startswith("projection uncertainty, 1 sigma: dark 0, yellow ")
    assert len(rec.column(f"{uncertainty}/contours", "LineStrips2D:strips")[0]) > 0
    # the camera model beside the view: the calibrated one, as ost.yaml holds it
    assert rec.column(cam, "CameraInfo:k")[-1] == info.k.reshape(-1).tolist()
    assert rec.column(cam, "CameraInfo:d")[-1] == info.d.tolist()
    verify = rerun_cli("rrd", "verify", str(out), cwd=tmp_path)
    assert verify.returncode == 0, verify.stderr


def test_resync_offsets_and_shared_frames(resynced_log: Path, tmp_path: Path) -> None:
    processed = tmp_path / "processed.mcap"
    from camlog.cli import main

    assert main(["process", str(resynced_log), "--topic", "/stereo_sync/left/image_raw",
                 "--red-pixels", "-o", str(processed), "--drop-input"]) == 0
    out = tmp_path / "synced.rrd"
    result = view_logs([resynced_log, processed], output=out, progress=False)
    rec = load_rrd(out)
    offsets = [m.point[0] for m in messages(resynced_log, "/stereo_sync/offset_s")
               if isinstance(m, PointStamped)]
    logged = rec.column("/metrics/stereo_offset_ms/stereo_sync", "Scalars:scalars")
    np.testing.assert_allclose([row[0] for row in logged], np.multiply(offsets, 1e3))
    assert "/stereo_sync/left" in result.cameras and "/unsynced/left" in result.cameras
    # /unsynced/left and /stereo_sync/left share a frame_id; the re-stamped outputs of the
    # processed /stereo_sync/left images are matched to that camera by stamp
    pairs = len(offsets)
    assert rec.count("/world/stereo_sync/left/red_pixels/mask", "SegmentationImage:buffer") \
        == pairs
    assert rec.count("/world/unsynced/left/red_pixels/mask", "SegmentationImage:buffer") == 0
    assert rec.count("/text/stereo_sync/stats", "TextDocument:text") == 1


def test_every_jpeg_window_and_topics(red_processed_log: Path, tmp_path: Path) -> None:
    out = tmp_path / "small.rrd"
    result = view_logs([red_processed_log], output=out, progress=False, start_s=0.1,
                       end_s=0.5, topics=["/stereo_camera/left/*"],
                       options=LoggerOptions(every=3, jpeg_quality=80))
    rec = load_rrd(out)
    # 0.1 s <= t < 0.5 s at 30 Hz: frames 3..14 (12 frames), every third kept
    assert rec.count(f"{LEFT}/image", "EncodedImage:blob") == 4
    assert rec.column(f"{LEFT}/image", "EncodedImage:media_type") == [["image/jpeg"]] * 4
    assert rec.count(f"{LEFT}/red_pixels/mask", "SegmentationImage:buffer") == 4
    assert rec.count("/metrics/red_pixel_count/stereo_camera/left", "Scalars:scalars") == 12
    assert RIGHT not in rec.rows and result.cameras == ["/stereo_camera/left"]


def test_the_default_output_sits_beside_the_log(red_log: Path, tmp_path: Path) -> None:
    log = tmp_path / "run.mcap"
    log.write_bytes(red_log.read_bytes())
    result = view_logs([log], progress=False)
    assert result.output == tmp_path / "run.rrd" and result.output.is_file()


def test_timelines_carry_log_time_and_header_stamp(tmp_path: Path) -> None:
    log = tmp_path / "late.mcap"
    stamps = [1_700_000_000_000_000_000 + i * 100_000_000 for i in range(4)]
    with open_writer(log) as writer:
        for i, stamp in enumerate(stamps):  # each stored 7 ms after its stamp
            pixels = np.full((8, 8), i, np.uint8)
            writer.write("/cam/image_raw", Image(stamp, "cam", "mono8", pixels),
                         log_time_ns=stamp + 7_000_000)
        writer.write("/notes", Text("done"), log_time_ns=stamps[-1] + 9_000_000)
    out = tmp_path / "late.rrd"
    view_logs([log], output=out, progress=False)
    rec = load_rrd(out)
    assert rec.time("/world/cam/image", "log_time") == [s + 7_000_000 for s in stamps]
    assert rec.time("/world/cam/image", "header_stamp") == stamps
    assert rec.time("/text/notes", "log_time") == [stamps[-1] + 9_000_000]
    assert rec.timelines["/text/notes"] == {"log_time"}  # a String has no header


def test_compressed_inputs_are_stored_as_they_are(red_log: Path, tmp_path: Path) -> None:
    from camlog.cli import main

    jpeg = tmp_path / "jpeg.mcap"
    assert main(["convert", str(red_log), str(jpeg), "--compress", "jpeg", "--no-progress"]) == 0
    processed = tmp_path / "png_outputs.mcap"
    assert main(["process", str(jpeg), "--topic", "/stereo_camera/left/image_raw/compressed",
                 "--red-pixels", "--edges", "--compress", "png", "-o", str(processed)]) == 0
    out = tmp_path / "compressed.rrd"
    view_logs([processed], output=out, progress=False, options=LoggerOptions(jpeg_quality=50))
    rec = load_rrd(out)
    assert rec.count(f"{LEFT}/image", "EncodedImage:blob") == 20
    assert rec.column(f"{LEFT}/image", "EncodedImage:media_type")[0] == ["image/jpeg"]
    assert rec.count(f"{LEFT}/image", "Image:buffer") == 0  # not decoded, not re-encoded
    # PNG processor outputs are decoded to classes: the same overlays as from raw images
    assert rec.count(f"{LEFT}/red_pixels/mask", "SegmentationImage:buffer") == 20
    assert rec.count(f"{LEFT}/edges", "SegmentationImage:buffer") == 20


def test_jpeg_images_of_a_distorted_camera_are_remapped_and_an_ideal_camera_is_as_before(
        tmp_path: Path) -> None:
    """A distorted camera's JPEG frames go into the recording as they are and are decoded
    (on the worker threads) to make its view; an ideal camera gets no view and keeps its
    entities, with its full model beside its Pinhole."""
    ideal = CameraModel.ideal(64, 48, 1.0)
    distorted = CameraModel(64, 48, ideal.k, "plumb_bob", np.array([-0.3, 0.1, 0, 0, 0]))
    log = tmp_path / "two.mcap"
    t0 = 1_700_000_000_000_000_000
    with open_writer(log) as writer:
        for i in range(4):
            stamp = t0 + i * 100_000_000
            pixels = np.full((48, 64, 3), 60 * i, np.uint8)
            frame = Frame(stamp, "lens", pixels, Color.RGB)
            writer.write("/lens/image_raw/compressed", encode_compressed(frame),
                         log_time_ns=stamp)
            writer.write("/lens/camera_info", distorted.camera_info(stamp_ns=stamp,
                                                                    frame_id="lens"),
                         log_time_ns=stamp)
            writer.write("/pin/image_raw", Image(stamp, "pin", "rgb8", pixels),
                         log_time_ns=stamp)
            writer.write("/pin/camera_info", ideal.camera_info(stamp_ns=stamp, frame_id="pin"),
                         log_time_ns=stamp)
        writer.write("/pin/calibration/uncertainty", Image(
            t0 + 400_000_000, "pin", "32FC1", np.full((48, 64), 0.05, np.float32)),
            log_time_ns=t0 + 400_000_000)
    out = tmp_path / "two.rrd"
    result = view_logs([log], output=out, progress=False)
    assert (result.images, result.remapped) == (8, 4) and result.warnings == []
    rec = load_rrd(out)
    assert rec.count("/raw/lens/image", "EncodedImage:blob") == 4
    assert rec.count("/world/lens/undistorted/image", "Image:buffer") == 4
    (image_format,) = rec.column("/world/lens/undistorted/image", "Image:format")[:1]
    assert (image_format[0]["width"], image_format[0]["height"]) == (32, 24)  # half size
    # the ideal camera: its image under its own Pinhole, as before, and its model beside it
    assert rec.count("/world/pin/image", "Image:buffer") == 4
    assert not [e for e in rec.rows if e.startswith(("/raw/pin", "/world/pin/undistorted"))]
    assert rec.entities_with(PINHOLE) == ["/world/lens/undistorted", "/world/pin"]
    assert rec.column("/world/pin", "CameraInfo:k") == [ideal.k.reshape(-1).tolist()]
    # its calibration's uncertainty map under its own Pinhole, as for any pinhole camera
    assert rec.count("/world/pin/calibration/uncertainty", "Image:buffer") == 1
