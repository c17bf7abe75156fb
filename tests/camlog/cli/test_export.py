"""``camlog export``: frames out of a log as files named by stamp (read back with OpenCV) or
one MP4 (read back with PyAV)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from camlog.cli import main
from replay import CompressedImage, Image
from replay.frames import decode_frame, encode_compressed
from tests.encodings import Case, colour_cases, compared, depth_cases, expected_rgb8
from tests.replay.samples import ROUND_TRIP_ENCODINGS, T0_NS, random_pixels, write_log

PERIOD_NS = 50_000_000  # 20 Hz
FRAMES = 6


@pytest.fixture(scope="module")
def every_encoding(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """FRAMES frames of every raw encoding on /cam/<encoding>, and a PNG-compressed topic."""
    entries = []
    for i in range(FRAMES):
        stamp = T0_NS + i * PERIOD_NS
        for encoding in ROUND_TRIP_ENCODINGS:
            pixels = random_pixels(encoding, seed=i)
            entries.append((f"/cam/{encoding}", stamp, Image(stamp, "cam", encoding, pixels)))
        png = encode_compressed(decode_frame(
            Image(stamp, "cam", "rgb8", random_pixels("rgb8", seed=i))), "png")
        entries.append(("/cam/compressed", stamp, CompressedImage(stamp, "cam", png.format,
                                                                  png.data)))
    path = tmp_path_factory.mktemp("export") / "every.mcap"
    write_log(path, entries)
    return path


def as_file_reads(encoding: str, pixels: np.ndarray) -> np.ndarray:
    """What cv2.imread(IMREAD_UNCHANGED) returns for a lossless export of ``pixels``."""
    match encoding:
        case "rgb8":
            return pixels[..., ::-1]
        case "rgba8":
            return pixels[..., [2, 1, 0, 3]]
    return pixels


@pytest.mark.parametrize("encoding", ROUND_TRIP_ENCODINGS)
def test_png_files_hold_the_pixels(every_encoding: Path, tmp_path: Path, encoding: str,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "frames"
    assert main(["export", str(every_encoding), "--topic", f"/cam/{encoding}", "-o", str(out),
                 "--no-progress"]) == 0
    assert capsys.readouterr().out.startswith(f"exported {FRAMES} frames of /cam/{encoding}")
    files = sorted(out.iterdir())
    assert [f.name for f in files] == [f"{T0_NS + i * PERIOD_NS:019d}.png" for i in range(FRAMES)]
    for i, file in enumerate(files):
        read = cv2.imread(str(file), cv2.IMREAD_UNCHANGED)
        expected = as_file_reads(encoding, random_pixels(encoding, seed=i))
        assert read.dtype == expected.dtype  # 16-bit stays 16-bit
        np.testing.assert_array_equal(read, expected)


CASES = {case.encoding: case for case in [*colour_cases(), *depth_cases()]}


@pytest.fixture(scope="module")
def every_camera_encoding(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One frame of every encoding camlog decodes (bayer, YUV, 16-bit colour, depth...)."""
    path = tmp_path_factory.mktemp("export") / "cases.mcap"
    write_log(path, [(f"/cam/{name}", T0_NS, Image(T0_NS, "cam", name, case.pixels))
                     for name, case in CASES.items()])
    return path


def read_back(path: Path, case: Case) -> np.ndarray:
    """An exported PNG as RGB (colour) or one channel, at the depth it was written."""
    read = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if read.ndim == 3:
        read = cv2.cvtColor(read[..., :3], cv2.COLOR_BGR2RGB)
    return read


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_camera_encoding_exports(every_camera_encoding: Path, tmp_path: Path,
                                       name: str) -> None:
    case = CASES[name]
    out = tmp_path / "frames"
    assert main(["export", str(every_camera_encoding), "--topic", f"/cam/{name}", "-o",
                 str(out), "--no-progress"]) == 0
    (file,) = out.iterdir()
    read = read_back(file, case)
    if case.depth_m is not None:  # depth: 16-bit millimetres
        assert read.dtype == np.uint16
        np.testing.assert_array_equal(read, np.round(case.depth_m * 1000).astype(np.uint16))
        return
    if read.dtype == np.uint16:  # 16-bit sources stay 16-bit
        assert name.endswith("16")
        read = (read >> 8).astype(np.uint8)
    expected = expected_rgb8(case)
    if read.ndim == 2:
        expected = expected[..., 0]
    keep = compared(case)
    difference = np.abs(read.astype(int) - expected.astype(int))[keep]
    assert difference.max() <= case.tolerance, (name, difference.max())


def test_compressed_jpg_every_and_window(every_encoding: Path, tmp_path: Path) -> None:
    out = tmp_path / "jpg"
    # window [0.1 s, 0.3 s) holds frames 2..5 (stamps 0.1, 0.15, 0.2, 0.25); every 2nd: 2, 4
    assert main(["export", str(every_encoding), "--topic", "/cam/compressed", "-o", str(out),
                 "--format", "jpg", "--every", "2", "--start", "0.1", "--end", "0.3",
                 "--no-progress"]) == 0
    assert [f.name for f in sorted(out.iterdir())] == [
        f"{T0_NS + i * PERIOD_NS:019d}.jpg" for i in (2, 4)]
    read = cv2.imread(str(sorted(out.iterdir())[0]))
    expected = random_pixels("rgb8", seed=2)[..., ::-1]
    assert read.shape == expected.shape  # JPEG: only the size is exact on random pixels


def test_bad_use_is_one_line(every_encoding: Path, tmp_path: Path,
                             capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x"
    for flags, needle in ((["--topic", "/cam/mono16", "--format", "jpg"], "JPEG cannot hold"),
                          (["--topic", "/nope"], "has no topic /nope"),
                          (["--topic", "/cam/rgb8", "--start", "9"], "no frames of /cam/rgb8")):
        code = main(["export", str(every_encoding), "-o", str(out), "--no-progress", *flags])
        err = capsys.readouterr().err
        assert code == 1 and err.count("\n") == 1 and needle in err, err
        assert not out.exists()
    out.mkdir()
    assert main(["export", str(every_encoding), "-o", str(out), "--topic", "/cam/rgb8",
                 "--no-progress"]) == 0
    code = main(["export", str(every_encoding), "-o", str(out), "--topic", "/cam/rgb8",
                 "--no-progress"])
    assert code == 1 and "--overwrite" in capsys.readouterr().err


def test_mp4_plays_back(red_log: Path, tmp_path: Path,
                        capsys: pytest.CaptureFixture[str]) -> None:
    import av  # the test extra installs camlog[video]

    out = tmp_path / "left.mp4"
    assert main(["export", str(red_log), "--topic", "/stereo_camera/left/image_raw", "-o",
                 str(out), "--no-progress"]) == 0
    assert "at 30.00 fps" in capsys.readouterr().out
    with av.open(str(out)) as container:
        frames = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
    assert len(frames) == 20 and frames[0].shape == (240, 320, 3)
    # the red block sits in the middle of the left image
    r, g, b = (float(c) for c in frames[0][110:130, 150:170].reshape(-1, 3).mean(axis=0))
    assert r > 2 * (g + b) / 2, (r, g, b)
