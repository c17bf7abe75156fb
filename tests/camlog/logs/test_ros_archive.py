"""camera_calibration's ``calibrationdata.tar.gz`` imported as it is, mono and stereo.

The archives are made as camera_calibration writes them (:mod:`tests.ros_archives`): a
rendered stereo rig's frames as ``left-NNNN.png`` / ``right-NNNN.png``, a calibration through
camlog's YAML and INI writers, packed with ``tarfile``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np
import pytest

from camlog.cli import main
from camlog.logs.importer import import_images
from camlog.logs.ros_archive import read_ros_archive
from camlog.requests.logs import ImportRequest
from replay import CameraInfo, Image, ImageFolderError, open_reader
from replay.calibration_ini import ost_text
from tests.outputs import temp_outputs
from tests.ros_archives import Rendered, pack, png, views, yaml


def shifted(info: CameraInfo, df: float) -> CameraInfo:
    """Another calibration of the camera: fx, fy moved by ``df`` px, k1 by -0.01."""
    k = info.k.copy()
    k[0, 0] += df
    k[1, 1] += df
    d = np.resize(info.d, 5).astype(np.float64)
    d[0] -= 0.01
    return dataclasses.replace(info, k=k, d=d, distortion_model="plumb_bob")


def imported(archive: Path, tmp_path: Path, camera: str | None = None) -> Path:
    out = tmp_path / "imported.mcap"
    import_images(ImportRequest(folder=archive, output=out, camera=camera, progress=False))
    return out


def messages(log: Path, topic: str) -> list[object]:
    with open_reader(log) as reader:
        return [r.message for r in reader.messages([topic])]


def assert_same_model(got: object, expected: CameraInfo) -> None:
    assert isinstance(got, CameraInfo)
    assert (got.width, got.height, got.distortion_model) == \
        (expected.width, expected.height, expected.distortion_model)
    for name in ("k", "d", "r", "p"):
        np.testing.assert_allclose(getattr(got, name), getattr(expected, name), atol=5e-6)


def test_a_mono_archive_is_one_camera_with_the_archives_calibration(
        rendered_rig: Rendered, tmp_path: Path) -> None:
    grey = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in rendered_rig.images[0]]
    theirs = shifted(rendered_rig.infos[0], 3.5)
    # written out of order, as a tar file may hold them: numbers give the order
    members = {f"left-{i:04d}.png": png(grey[i]) for i in reversed(range(len(grey)))}
    members |= {"ost.yaml": yaml(theirs, "narrow_stereo"), "ost.txt": ost_text(theirs).encode()}
    archive = pack(tmp_path / "calibrationdata.tar.gz", members)
    log = imported(archive, tmp_path)
    got = messages(log, "/camera/image_raw")
    assert len(got) == len(grey)
    for message, expected in zip(got, grey, strict=True):
        assert isinstance(message, Image) and message.encoding == "mono8"
        np.testing.assert_array_equal(message.pixels, expected)
    stamps = [m.stamp_ns for m in got if isinstance(m, Image)]
    assert np.all(np.diff(stamps) == 100_000_000)
    infos = messages(log, "/camera/camera_info")
    assert len(infos) == len(grey)
    assert_same_model(infos[0], theirs)
    assert archive.is_file() and not temp_outputs(tmp_path)


def test_a_stereo_archive_is_a_pair_under_one_stamp(rendered_rig: Rendered,
                                                     tmp_path: Path) -> None:
    left, right = (shifted(info, 2.0 * side) for side, info in enumerate(rendered_rig.infos))
    members = views(rendered_rig) | {"left.yaml": yaml(left, "narrow_stereo/left"),
                                     "right.yaml": yaml(right, "narrow_stereo/right"),
                                     "ost.txt": ost_text(left=left, right=right).encode()}
    log = imported(pack(tmp_path / "calibrationdata.tar.gz", members), tmp_path,
                   camera="/rig")
    for side, expected in enumerate((left, right)):
        name = ("left", "right")[side]
        got = [m for m in messages(log, f"/rig/{name}/image_raw") if isinstance(m, Image)]
        assert [m.encoding for m in got] == ["rgb8"] * len(rendered_rig.images[side])
        for message, pixels in zip(got, rendered_rig.images[side], strict=True):
            np.testing.assert_array_equal(message.pixels, pixels)
        assert_same_model(messages(log, f"/rig/{name}/camera_info")[0], expected)
    left_stamps = [m.stamp_ns for m in messages(log, "/rig/left/image_raw")
                   if isinstance(m, Image)]
    right_stamps = [m.stamp_ns for m in messages(log, "/rig/right/image_raw")
                    if isinstance(m, Image)]
    assert left_stamps == right_stamps


def test_an_older_archive_has_its_calibration_in_ost_txt_only(
        rendered_rig: Rendered, tmp_path: Path) -> None:
    # camera_calibration's stereo ost.txt repeats its header before the right camera; the
    # members sit in a folder of the archive
    left, right = rendered_rig.infos
    text = ost_text(left).replace("[narrow_stereo]", "[narrow_stereo/left]") + \
        ost_text(right).replace("[narrow_stereo]", "[narrow_stereo/right]")
    members = views(rendered_rig, folder="calibrationdata/")
    members["calibrationdata/ost.txt"] = text.encode()
    found = read_ros_archive(pack(tmp_path / "old.tgz", members))
    assert found.stereo and len(found.frames) == len(rendered_rig.images[0])
    assert found.calibration_files == ["calibrationdata/ost.txt"] * 2
    for got, expected in zip(found.calibration, (left, right), strict=True):
        # ost.txt holds 6 decimals
        for name in ("k", "d", "r", "p"):
            np.testing.assert_allclose(getattr(got, name), getattr(expected, name), atol=5e-7)


def test_a_stereo_archive_without_calibration_imports_its_images(
        rendered_rig: Rendered, tmp_path: Path) -> None:
    log = imported(pack(tmp_path / "calibrationdata.tar.gz", views(rendered_rig)), tmp_path)
    assert len(messages(log, "/stereo/left/image_raw")) == len(rendered_rig.images[0])
    assert messages(log, "/stereo/left/camera_info") == []


BAD = {
    "no images": ({"ost.yaml": b"image_width: 4\n"}, [], "no left-NNNN.png images"),
    "a right image without its left": (
        {**{f"left-{i:04d}.png": b"" for i in range(3)},
         **{f"right-{i:04d}.png": b"" for i in range(4)}},
        [], "3 left and 4 right images, and right-0003.png has no partner"),
    "unreadable yaml": ({"left-0000.png": b"", "ost.yaml": b"camera_matrix: [1, 2\n"}, [],
                        "ost.yaml: not valid YAML"),
    "a yaml without its matrices": ({"left-0000.png": b"", "ost.yaml": b"image_width: 4\n"},
                                    [], "ost.yaml: missing image_height"),
    "an ost.txt of two cameras for one": (
        {"left-0000.png": b"", "ost.txt": b"[image]\n\nwidth\n4\n\nheight\n3\n\n[a]\n\n"
                                          b"camera matrix\n1 0 0\n0 1 0\n0 0 1\n\ndistortion"
                                          b"\n0 0 0 0 0\n\nrectification\n1 0 0\n0 1 0\n"
                                          b"0 0 1\n\nprojection\n1 0 0 0\n0 1 0 0\n0 0 1 0"
                                          b"\n\n[b]\n\ncamera matrix\n1 0 0\n0 1 0\n0 0 1\n"},
        [], "ost.txt: [b]: missing distortion"),
    "--stereo on one camera's archive": ({"left-0000.png": b""}, ["--stereo"],
                                         "--stereo, but the archive holds one camera's"),
    "an undecodable image": ({"left-0000.png": b"not a png"}, [],
                             "left-0000.png: not a readable image file"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_a_bad_archive_is_one_error_line(case: str, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    members, options, words = BAD[case]
    archive = pack(tmp_path / "calibrationdata.tar.gz", members)
    out = tmp_path / "out.mcap"
    assert main(["import", str(archive), "-o", str(out), *options, "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("camlog import: error: ") and err.count("\n") == 1, err
    assert words in err and str(archive) in err
    assert not out.exists() and not temp_outputs(tmp_path)


def test_a_damaged_archive_is_one_error_line(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    good = pack(tmp_path / "good.tar.gz", {f"left-{i:04d}.png": bytes(5000) for i in range(4)})
    cut = tmp_path / "calibrationdata.tar.gz"
    cut.write_bytes(good.read_bytes()[:-40])
    assert main(["import", str(cut), "-o", str(tmp_path / "o.mcap"), "--no-progress"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a readable tar archive" in err
    with pytest.raises(ImageFolderError, match="not a readable tar archive"):
        read_ros_archive(cut)
