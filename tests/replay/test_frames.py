"""Frames: the decoder and encoder tables, against OpenCV's own conversions."""

from __future__ import annotations

import doctest
import struct
from pathlib import Path

import cv2
import numpy as np
import pytest
import rerun as rr

import replay.frames.compressed
import replay.frames.lookup
from processors.red_pixels import CENTROID, COUNT, RedPixels
from replay import (
    IMAGE_ENCODINGS,
    CompressedImage,
    CompressedVideo,
    EncodingError,
    Image,
    PointStamped,
    open_reader,
)
from replay.frames import (
    DECODERS,
    ENCODERS,
    Color,
    Frame,
    FrameStream,
    decode_frame,
    decompress,
    encode_compressed,
    encode_image,
    raw_encoding,
)
from rerun_export.images import rerun_image
from tests.encodings import (
    COLS,
    RED_CENTROID,
    ROWS,
    Case,
    colour_cases,
    compared,
    depth_cases,
    expected_rgb8,
    mosaic,
    scene_depth_m,
    scene_rgb,
)

from .samples import random_pixels, write_log


def _smooth_rgb(height: int = 48, width: int = 64) -> np.ndarray:
    """Gradients JPEG reproduces closely: ``(H, W, 3)`` uint8."""
    y, x = np.mgrid[0:height, 0:width]
    return np.stack([x * 255 // width, y * 255 // height, (x + y) * 255 // (width + height)],
                    axis=-1).astype(np.uint8)


CASES = {case.encoding: case for case in colour_cases() + depth_cases()}
ALIASES = {"uyvy": "yuv422", "yuyv": "yuv422_yuy2"}


def test_every_raw_encoding_has_a_case() -> None:
    assert set(IMAGE_ENCODINGS) == set(CASES) | set(ALIASES) | {"16SC1"}


@pytest.mark.parametrize("case", colour_cases(), ids=lambda c: c.encoding)
def test_colour_encodings_decode_to_the_scene(case: Case) -> None:
    frame = decode_frame(Image(11, "cam", case.encoding, case.pixels))
    assert (frame.stamp_ns, frame.frame_id, frame.source) == (11, "cam", case.encoding)
    keep = compared(case)
    error = np.abs(frame.rgb8().astype(int) - expected_rgb8(case).astype(int))[keep]
    assert error.max() <= case.tolerance
    grey = cv2.cvtColor(expected_rgb8(case), cv2.COLOR_RGB2GRAY).astype(int)
    assert np.abs(frame.mono8().astype(int) - grey)[keep].max() <= case.tolerance + 1
    outputs = dict(RedPixels()(frame))
    if case.colour:
        centroid = outputs[CENTROID]
        assert isinstance(centroid, PointStamped)
        # demosaicing shifts the red edge by a fraction of a pixel
        within = 0.5 if case.margin else 0.01
        assert tuple(centroid.point[:2]) == pytest.approx(RED_CENTROID, abs=within)
    else:
        assert CENTROID not in outputs


@pytest.mark.parametrize("wrong", ["bggr", "gbrg", "grbg"])
def test_a_wrong_bayer_pattern_loses_the_red_square(wrong: str) -> None:
    pixels = mosaic(scene_rgb(), "rggb")
    inside = (ROWS.stop - ROWS.start - 2) * (COLS.stop - COLS.start - 2)  # one pixel in

    def red_count(encoding: str) -> float:
        count = dict(RedPixels()(decode_frame(Image(0, "", encoding, pixels))))[COUNT]
        assert isinstance(count, PointStamped)
        return float(count.point[0])

    assert red_count("bayer_rggb8") >= inside
    assert red_count(f"bayer_{wrong}8") < inside / 2


def test_decoding_a_raw_image_copies_nothing() -> None:
    pixels = scene_rgb()
    assert np.shares_memory(decode_frame(Image(0, "", "rgb8", pixels)).pixels, pixels)


@pytest.mark.parametrize("case", depth_cases(), ids=lambda c: c.encoding)
def test_depth_decodes_with_its_metre_scale(case: Case) -> None:
    frame = decode_frame(Image(0, "cam", case.encoding, case.pixels))
    assert frame.color is Color.DEPTH and frame.depth_unit_m is not None
    assert case.depth_m is not None
    np.testing.assert_allclose(frame.pixels * frame.depth_unit_m, case.depth_m, atol=1e-6)
    archetype = rerun_image(frame)
    assert isinstance(archetype, rr.DepthImage)
    meter = archetype.meter.pa_array.to_pylist()[0]  # type: ignore[union-attr]
    assert meter == pytest.approx(1.0 / frame.depth_unit_m)


def _compressed_depth(encoding: str, png: np.ndarray, quant: tuple[float, float]) -> bytes:
    """compressed_depth_image_transport's layout, built from its documentation: int32
    format, float32 depthParam[2], then the PNG."""
    ok, buf = cv2.imencode(".png", png)
    assert ok
    return struct.pack("<iff", 0, *quant) + buf.tobytes()


def test_compressed_depth_16uc1_is_exact_and_32fc1_within_quantisation() -> None:
    depth = scene_depth_m()
    mm = np.round(depth * 1000).astype(np.uint16)
    data = _compressed_depth("16UC1", mm, (0.0, 0.0))
    frame = decode_frame(CompressedImage(1, "d", "16UC1; compressedDepth png", data))
    assert frame.depth_unit_m == 0.001 and np.array_equal(frame.pixels, mm)
    a = 100.0 * 101.0  # the transport's defaults: depth_quantization 100, depth_max 10 m
    b = 1.0 - a / 10.0
    inverse = np.where(depth > 0, np.round(a / np.maximum(depth, 1e-6) + b), 0)
    data = _compressed_depth("32FC1", inverse.astype(np.uint16), (a, b))
    frame = decode_frame(CompressedImage(1, "d", "32FC1; compressedDepth png", data))
    assert frame.depth_unit_m == 1.0
    measured = depth > 0
    assert np.isnan(frame.pixels[~measured]).all()
    # one quantisation step of inverse depth at 2 m is a / 2^2 ... about 0.4 mm
    np.testing.assert_allclose(frame.pixels[measured], depth[measured], atol=1e-3)
    again = decode_frame(encode_compressed(frame, "compressedDepth"))
    np.testing.assert_allclose(again.pixels[measured], depth[measured], atol=1e-3)
    mm_frame = decode_frame(Image(0, "d", "16UC1", mm))
    assert np.array_equal(decode_frame(encode_compressed(mm_frame, "compressedDepth")).pixels, mm)


@pytest.mark.parametrize("encoding", sorted(e for t, e in ENCODERS if t is Image))
def test_every_writable_encoding_round_trips_a_frame(encoding: str) -> None:
    pixels = random_pixels(encoding, height=4, width=6, seed=3)
    frame = decode_frame(Image(1, "cam", encoding, pixels))
    assert encode_image(frame, encoding) == Image(1, "cam", encoding, pixels)
    if encoding in ALIASES.values() or encoding.startswith("bayer"):
        return
    again = decode_frame(encode_image(frame))  # its natural encoding
    assert np.array_equal(again.pixels, frame.pixels) and again.color is frame.color


def test_encode_converts_colour_order_and_depth() -> None:
    rgb = random_pixels("rgb8")
    frame = decode_frame(Image(0, "c", "rgb8", rgb))
    assert np.array_equal(encode_image(frame, "bgr8").pixels, rgb[:, :, ::-1])
    rgba = encode_image(frame, "rgba8").pixels
    assert np.array_equal(rgba[:, :, :3], rgb) and (rgba[:, :, 3] == 255).all()
    mono16 = encode_image(decode_frame(Image(0, "c", "mono8", rgb[:, :, 0])), "mono16")
    deep = encode_image(frame, "rgb16").pixels
    assert np.array_equal(deep, rgb.astype(np.uint16) * 257)
    assert np.array_equal(mono16.pixels, rgb[:, :, 0].astype(np.uint16) * 257)
    with pytest.raises(EncodingError, match="cannot write images as 'yuv411'"):
        encode_image(frame, "yuv411")


@pytest.mark.parametrize("encoding", ["rgb8", "bgr8", "mono8", "mono16"])
def test_png_round_trip_restores_the_original_encoding(encoding: str) -> None:
    image = Image(5, "cam", encoding, random_pixels(encoding, height=10, width=12))
    compressed = encode_compressed(decode_frame(image), "png")
    assert compressed.format.startswith(f"{encoding}; png compressed ")
    frame = decode_frame(compressed)
    assert (frame.stamp_ns, frame.frame_id, frame.source) == (5, "cam", "png")
    assert decompress(compressed, frame) == image


def test_png_of_rgba_drops_alpha_exactly() -> None:
    pixels = random_pixels("rgba8")
    frame = decode_frame(encode_compressed(decode_frame(Image(0, "cam", "rgba8", pixels)), "png"))
    assert frame.color is Color.BGR and np.array_equal(frame.rgb8(), pixels[:, :, :3])


def test_jpeg_round_trip_is_close() -> None:
    pixels = _smooth_rgb()
    compressed = encode_compressed(decode_frame(Image(9, "cam", "rgb8", pixels)), "jpeg",
                                   jpeg_quality=95)
    assert compressed.data[:2] == b"\xff\xd8"
    assert compressed.format == "rgb8; jpeg compressed bgr8"
    decoded = decompress(compressed, decode_frame(compressed))
    assert decoded.encoding == "rgb8" and decoded.pixels.shape == pixels.shape
    error = np.abs(decoded.pixels.astype(np.int16) - pixels.astype(np.int16))
    assert error.mean() < 2.0
    assert error.max() < 24


def test_compression_errors() -> None:
    mono16 = decode_frame(Image(0, "cam", "mono16", random_pixels("mono16")))
    with pytest.raises(EncodingError, match="JPEG cannot hold mono16"):
        encode_compressed(mono16, "jpeg")
    with pytest.raises(EncodingError, match="'webp'"):
        encode_compressed(mono16, "webp")
    with pytest.raises(EncodingError, match="cannot decode compressed image"):
        decode_frame(CompressedImage(0, "cam", "jpeg", b"not a jpeg"))
    with pytest.raises(EncodingError, match="cannot decode compressed image"):
        decode_frame(CompressedImage(0, "cam", "jpeg", b""))
    with pytest.raises(EncodingError, match="unsupported compressed image format 'tiff'"):
        decode_frame(CompressedImage(0, "cam", "tiff", b"II*\x00"))


@pytest.mark.parametrize("fmt", ["jpeg", "png"])
def test_compressed_images_from_a_log_decode(tmp_path: Path, fmt: str) -> None:
    pixels = _smooth_rgb()
    compressed = encode_compressed(decode_frame(Image(3, "cam", "rgb8", pixels)), fmt)
    write_log(tmp_path / "c.mcap", [("/cam/compressed", 3, compressed)])
    with open_reader(tmp_path / "c.mcap") as reader:
        (record,) = reader.frames()
    assert record.topic == "/cam/compressed" and record.message.source == fmt
    error = np.abs(record.message.rgb8().astype(np.int16) - pixels.astype(np.int16))
    assert error.max() == 0 if fmt == "png" else error.mean() < 2.0


def test_frame_checks_its_pixels_against_its_colour_order() -> None:
    with pytest.raises(ValueError, match="3 channel"):
        Frame(0, "", np.zeros((2, 2), np.uint8), Color.RGB)
    with pytest.raises(ValueError, match="depth unit"):
        Frame(0, "", np.zeros((2, 2), np.uint16), Color.DEPTH)


def test_every_decoder_key_is_a_record_kind_and_a_name() -> None:
    assert all(kind in (Image, CompressedImage, CompressedVideo) and name
               for kind, name in DECODERS)


def test_docstring_examples() -> None:
    for module in (replay.frames.compressed, replay.frames.lookup):
        result = doctest.testmod(module)
        assert result.attempted > 0 and result.failed == 0


def test_an_unknown_encoding_is_named_with_the_table_s_choices() -> None:
    frame = decode_frame(Image(0, "c", "mono8", np.zeros((2, 2), np.uint8)))
    raw = ", ".join(sorted(IMAGE_ENCODINGS))
    writable = ", ".join(sorted(e for kind, e in ENCODERS if kind is Image))
    calls = [
        (lambda: raw_encoding("yuv411"), f"unsupported image encoding 'yuv411' (supported: {raw})"),
        (lambda: decode_frame(CompressedImage(0, "c", "tiff", b"")),
         "unsupported compressed image format 'tiff' (supported: compressedDepth, jpeg, png)"),
        (lambda: FrameStream().decode(CompressedVideo(0, "c", "av1", b"")),
         "unsupported video format 'av1' (supported: h264, h265)"),
        (lambda: encode_image(frame, "yuv411"), f"cannot write images as 'yuv411' "
                                                f"(writable: {writable})"),
        (lambda: encode_compressed(frame, "webp"), "unsupported compression 'webp' (use "
                                                   "compressedDepth or jpeg or png)"),
    ]
    for call, text in calls:
        with pytest.raises(EncodingError) as raised:
            call()
        assert str(raised.value) == text


def _rvl(depth: np.ndarray) -> bytes:
    """RVL as Wilson's paper ("Fast Lossless Depth Image Compression", 2017) and
    compressed_depth_image_transport's RvlCodec write it, one value at a time: a count of
    zeros, a count of non-zero pixels, their zigzag-coded differences from the previous
    non-zero pixel; each value in 3-bit nibbles (low first, 8 = another follows), eight
    nibbles to a little-endian 32-bit word, the first in its top bits."""
    words: list[int] = []
    word = count = 0

    def put(value: int) -> None:
        nonlocal word, count
        while True:
            nibble, value = value & 7, value >> 3
            word = (word << 4 | nibble | (8 if value else 0)) & 0xFFFFFFFF
            count += 1
            if count == 8:
                words.append(word)
                word = count = 0
            if not value:
                return

    flat, i, previous = [int(v) for v in depth.reshape(-1)], 0, 0
    while i < len(flat):
        zeros = 0
        while i < len(flat) and flat[i] == 0:
            zeros, i = zeros + 1, i + 1
        put(zeros)
        run = 0
        while i + run < len(flat) and flat[i + run]:
            run += 1
        put(run)
        for current in flat[i:i + run]:
            delta = current - previous
            put((delta << 1) ^ (delta >> 31))
            previous = current
        i += run
    if count:
        words.append((word << 4 * (8 - count)) & 0xFFFFFFFF)
    return struct.pack(f"<{len(words)}I", *words)


def _rvl_message(encoding: str, image: np.ndarray, quant: tuple[float, float]) -> CompressedImage:
    """compressedDepth RVL: the transport's header, uint32 width and height, the stream."""
    height, width = image.shape
    data = struct.pack("<iffII", 0, *quant, width, height) + _rvl(image)
    return CompressedImage(3, "d", f"{encoding}; compressedDepth rvl", data)


def test_compressed_depth_rvl_round_trips_exactly() -> None:
    depth = scene_depth_m()
    mm = np.round(depth * 1000).astype(np.uint16)
    frame = decode_frame(_rvl_message("16UC1", mm, (0.0, 0.0)))
    assert frame.depth_unit_m == 0.001 and np.array_equal(frame.pixels, mm)
    # every difference size, wrap-around included, and zero runs at both ends
    rng = np.random.default_rng(5)
    values = rng.integers(0, 65536, (48, 64), dtype=np.uint16)
    values[rng.random((48, 64)) < 0.3] = 0
    values[0, :5] = values[-1, -7:] = 0
    frame = decode_frame(_rvl_message("16UC1", values, (0.0, 0.0)))
    assert np.array_equal(frame.pixels, values)
    a = 100.0 * 101.0
    b = 1.0 - a / 10.0
    inverse = np.where(depth > 0, np.round(a / np.maximum(depth, 1e-6) + b), 0).astype(np.uint16)
    frame = decode_frame(_rvl_message("32FC1", inverse, (a, b)))
    measured = depth > 0
    assert np.isnan(frame.pixels[~measured]).all()
    np.testing.assert_allclose(frame.pixels[measured], depth[measured], atol=1e-3)


def test_a_cut_rvl_stream_does_not_decode() -> None:
    message = _rvl_message("16UC1", np.round(scene_depth_m() * 1000).astype(np.uint16),
                           (0.0, 0.0))
    cut = CompressedImage(3, "d", message.format, message.data[: len(message.data) // 2])
    with pytest.raises(EncodingError, match="RVL stream"):
        decode_frame(cut)
