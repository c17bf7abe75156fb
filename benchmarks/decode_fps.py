"""Frame decoding throughput per encoding against OpenCV's (or PyAV's) bare conversion of the
same buffers, in one run.

For each encoding, the same 640x480 buffers are turned into RGB:

* ``bare``: the one OpenCV call that converts them (``cvtColor`` / ``imdecode``), or for
  H.264 PyAV's own decode loop (``CodecContext.decode`` + ``to_ndarray``);
* ``camlog``: ``decode_frame(message).rgb8()`` (``FrameStream`` for video), i.e. the table
  lookup, the typed frame and its conversion.

Target: camlog >= 0.8 x bare for every encoding (the seam adds no real work).

    python -m benchmarks.decode_fps [--frames N] [--repeats R]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import cv2
import numpy as np

from replay import CompressedImage, CompressedVideo, Image
from replay.frames import FrameStream, VideoEncoder, decode_frame, encode_compressed

from .docs import add_write_docs
from .report import emit, write_summary_rows

WIDTH, HEIGHT = 640, 480


def _scene(index: int) -> np.ndarray:
    """A textured RGB picture that moves with ``index`` (so video has work to do)."""
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    rgb = np.stack([(x + 3 * index) % 256, (y * 2) % 256, (x + y) % 256], axis=-1)
    return rgb.astype(np.uint8)


def _cases(frames: int) -> dict[str, tuple[list[object], Callable[[object], np.ndarray]]]:
    """encoding -> (messages, the bare conversion of one message to RGB)."""
    scenes = [_scene(i) for i in range(frames)]
    cases: dict[str, tuple[list[object], Callable[[object], np.ndarray]]] = {}

    def raw(encoding: str, convert: Callable[[np.ndarray], np.ndarray], code: int) -> None:
        messages: list[object] = [Image(i, "cam", encoding, convert(s))
                                  for i, s in enumerate(scenes)]
        cases[encoding] = (messages, lambda m: cv2.cvtColor(m.pixels, code))  # type: ignore[attr-defined]

    raw("bgr8", lambda s: cv2.cvtColor(s, cv2.COLOR_RGB2BGR), cv2.COLOR_BGR2RGB)
    raw("rgba8", lambda s: cv2.cvtColor(s, cv2.COLOR_RGB2RGBA), cv2.COLOR_RGBA2RGB)
    raw("mono8", lambda s: cv2.cvtColor(s, cv2.COLOR_RGB2GRAY), cv2.COLOR_GRAY2RGB)
    raw("bayer_rggb8", _mosaic, cv2.COLOR_BayerRGGB2RGB)
    raw("yuv422", lambda s: cv2.cvtColor(s, cv2.COLOR_RGB2YUV_UYVY), cv2.COLOR_YUV2RGB_UYVY)
    for fmt in ("jpeg", "png"):
        stills: list[object] = [
            encode_compressed(decode_frame(Image(i, "cam", "rgb8", s)), fmt)
            for i, s in enumerate(scenes)]
        cases[fmt] = (stills, _bare_still)
    try:
        encoder = VideoEncoder("h264")
        video: list[object] = [encoder(decode_frame(Image(i, "cam", "rgb8", s)))
                               for i, s in enumerate(scenes)]
        cases["h264"] = (video, _unused)  # decoded by _bare_video
    except Exception as err:
        print(f"h264 skipped: {err}")
    return cases


def _bare_still(message: object) -> np.ndarray:
    """OpenCV's own decode of one compressed still to RGB."""
    assert isinstance(message, CompressedImage)
    bgr = cv2.imdecode(np.frombuffer(message.data, np.uint8), cv2.IMREAD_COLOR)
    assert bgr is not None
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def _unused(message: object) -> np.ndarray:
    """Placeholder for video, whose bare loop (:func:`_bare_video`) keeps its codec state."""
    raise AssertionError("video is decoded by _bare_video")


def _mosaic(rgb: np.ndarray) -> np.ndarray:
    out = np.empty(rgb.shape[:2], np.uint8)
    out[0::2, 0::2], out[0::2, 1::2] = rgb[0::2, 0::2, 0], rgb[0::2, 1::2, 1]
    out[1::2, 0::2], out[1::2, 1::2] = rgb[1::2, 0::2, 1], rgb[1::2, 1::2, 2]
    return out


def _fps_pair(messages: list[object], bare: Callable[[list[object]], None],
              mine: Callable[[list[object]], None], repeats: int) -> tuple[float, float]:
    """Frames per second of both loops: warmed up once, then alternated, best of each."""
    bare(messages[:2])
    mine(messages[:2])
    best = [float("inf"), float("inf")]
    for _ in range(repeats):
        for index, run in enumerate((bare, mine)):
            started = time.perf_counter()
            run(messages)
            best[index] = min(best[index], time.perf_counter() - started)
    return len(messages) / best[0], len(messages) / best[1]


def _bare_video(messages: list[object]) -> None:
    import av

    codec = av.CodecContext.create("h264", "r")
    for message in messages:
        assert isinstance(message, CompressedVideo)
        for picture in codec.decode(av.Packet(message.data)):
            picture.to_ndarray(format="rgb24")


def _camlog(messages: list[object]) -> None:
    stream = FrameStream()
    for message in messages:
        assert isinstance(message, Image | CompressedImage | CompressedVideo)
        frame = stream.decode(message)
        if frame is not None:
            frame.rgb8()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--frames", type=int, default=60, help="frames per encoding (60)")
    parser.add_argument("--repeats", type=int, default=3, help="best of R runs (3)")
    args = parser.parse_args()
    cv2.setNumThreads(1)  # both sides on one core: the ratio is the seam's overhead
    for encoding, (messages, bare) in _cases(args.frames).items():
        def bare_loop(ms: list[object], b: Callable[[object], np.ndarray] = bare) -> None:
            for m in ms:
                b(m)

        bare_fps, mine = _fps_pair(messages, _bare_video if encoding == "h264" else bare_loop,
                                   _camlog, args.repeats)
        baseline = "PyAV decode loop" if encoding == "h264" else "OpenCV bare conversion"
        print(f"{encoding:12} {baseline}: {bare_fps:8.0f} frames/s   camlog: {mine:8.0f} "
              f"frames/s = {mine / bare_fps:.2f} x")
        emit(f"decode {encoding} 640x480", baseline=baseline, baseline_value=bare_fps,
             measured="decode_frame().rgb8()", measured_value=mine, unit="fps",
             ratio=mine / bare_fps, target=">= 0.8")
    write_summary_rows("decode_fps", args)


if __name__ == "__main__":
    main()
