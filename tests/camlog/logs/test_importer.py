"""``import_images``: folders of image files as camera logs."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from camlog.logs.importer import import_images, natural_key, pair_image_files
from camlog.requests.logs import ImportRequest
from replay import CameraInfo, Image, ImageFolderError, OptionError, open_reader
from replay.calibration_yaml import save_calibration
from replay.camera import CameraModel
from replay.format_names import DEFAULT_START_NS
from tests.outputs import temp_outputs


def pattern(seed: int, shape: tuple[int, ...], dtype: type = np.uint8) -> np.ndarray:
    high = 65535 if dtype == np.uint16 else 255
    return np.random.default_rng(seed).integers(0, high, shape, dtype=dtype, endpoint=True)


def images(path: Path, topic: str) -> list[Image]:
    with open_reader(path) as reader:
        return [r.message for r in reader.messages([topic]) if isinstance(r.message, Image)]


def test_natural_order() -> None:
    names = ["frame10.png", "frame9.png", "Frame1.png", "frame100.png", "a.png"]
    assert sorted(names, key=natural_key) == ["a.png", "Frame1.png", "frame9.png",
                                              "frame10.png", "frame100.png"]


def test_every_file_kind_keeps_its_pixels(tmp_path: Path) -> None:
    folder = tmp_path / "imgs"
    folder.mkdir()
    bgr = pattern(0, (24, 32, 3))
    gray, deep = pattern(1, (24, 32)), pattern(2, (24, 32), np.uint16)
    files = {"img1.png": bgr, "img2.ppm": bgr, "img3.pgm": gray, "img10.pgm": deep,
             "img11.png": deep, "img12.jpg": bgr}
    for name, array in files.items():
        assert cv2.imwrite(str(folder / name), array)
    (folder / "notes.txt").write_text("not an image")
    out = tmp_path / "log.mcap"
    result = import_images(ImportRequest(folder=folder, output=out, camera="/cam/image_raw",
                                         rate=20.0, progress=False))
    got = images(out, "/cam/image_raw")
    assert result.frames == 6 and result.topics == ["/cam/image_raw"]
    assert [m.stamp_ns for m in got] == [DEFAULT_START_NS + i * 50_000_000 for i in range(6)]
    assert [m.encoding for m in got] == ["rgb8", "rgb8", "mono8", "mono16", "mono16", "rgb8"]
    rgb = bgr[:, :, ::-1]
    for message, expected in zip(got[:5], [rgb, rgb, gray, deep, deep], strict=True):
        np.testing.assert_array_equal(message.pixels, expected)
    decoded = cv2.cvtColor(cv2.imread(str(folder / "img12.jpg")), cv2.COLOR_BGR2RGB)
    np.testing.assert_array_equal(got[5].pixels, decoded)  # JPEG: as OpenCV decodes it
    assert {m.frame_id for m in got} == {"cam_optical_frame"}


def test_stereo_pairs_share_stamps_and_camera_info(tmp_path: Path) -> None:
    folder = tmp_path / "stereo"
    folder.mkdir()
    for i in (3, 4, 12):
        for side, seed in (("left", i), ("right", 100 + i)):
            cv2.imwrite(str(folder / f"{side}{i:04d}.png"), pattern(seed, (24, 32)))
    cv2.imwrite(str(folder / "left0099.png"), pattern(9, (24, 32)))
    calibrations = []
    for side in ("left", "right"):
        info = CameraModel.ideal(32, 24, 1.0).camera_info(stamp_ns=0, frame_id=side)
        calibrations.append(tmp_path / f"{side}.yaml")
        save_calibration(calibrations[-1], info, camera_name=side)
    out = tmp_path / "stereo_bag"
    result = import_images(ImportRequest(folder=folder, output=out, stereo=True, camera="/rig",
                                         camera_info=calibrations, start_time=5, progress=False))
    assert [p.name for p in result.skipped] == ["left0099.png"]
    left, right = images(out, "/rig/left/image_raw"), images(out, "/rig/right/image_raw")
    assert [m.stamp_ns for m in left] == [m.stamp_ns for m in right] == [5, 100_000_005,
                                                                         200_000_005]
    np.testing.assert_array_equal(right[2].pixels, pattern(112, (24, 32)))
    assert left[0].frame_id == "rig_left_optical_frame"
    with open_reader(out) as reader:
        infos = [r.message for r in reader.messages(["/rig/right/camera_info"])]
    assert len(infos) == 3 and isinstance(infos[0], CameraInfo)
    assert infos[0].frame_id == "rig_right_optical_frame" and infos[0].width == 32


def test_stereo_pairing_by_suffix() -> None:
    files = [Path(n) for n in ("left_a.png", "right_a.jpg", "left_b.png", "right_c.png", "x.png")]
    pairs, alone = pair_image_files(files)
    assert [(a.name, b.name) for a, b in pairs] == [("left_a.png", "right_a.jpg")]
    assert [p.name for p in alone] == ["left_b.png", "right_c.png", "x.png"]


def test_bad_folders(tmp_path: Path) -> None:
    out = tmp_path / "out.mcap"
    with pytest.raises(ImageFolderError, match="does not exist"):
        import_images(ImportRequest(folder=tmp_path / "missing", output=out, progress=False))
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "readme.md").write_text("x")
    with pytest.raises(ImageFolderError, match="has no image files"):
        import_images(ImportRequest(folder=empty, output=out, progress=False))
    bad = tmp_path / "bad"
    bad.mkdir()
    cv2.imwrite(str(bad / "a1.png"), pattern(0, (8, 8)))
    (bad / "a2.png").write_bytes(b"\x89PNG broken")
    with pytest.raises(ImageFolderError, match=r"a2\.png: not a readable image"):
        import_images(ImportRequest(folder=bad, output=out, progress=False))
    sizes = tmp_path / "sizes"
    sizes.mkdir()
    cv2.imwrite(str(sizes / "a1.png"), pattern(0, (8, 8)))
    cv2.imwrite(str(sizes / "a2.png"), pattern(0, (9, 8)))
    with pytest.raises(ImageFolderError, match=r"a2\.png is 8x9, but .* 8x8"):
        import_images(ImportRequest(folder=sizes, output=out, progress=False))
    with pytest.raises(ImageFolderError, match="no left\\*/right\\* file pairs"):
        import_images(ImportRequest(folder=sizes, output=out, stereo=True, progress=False))
    with pytest.raises(OptionError, match="--rate"):
        import_images(ImportRequest(folder=sizes, output=out, rate=0.0, progress=False))
    assert not out.exists() and temp_outputs(out.parent) == []
