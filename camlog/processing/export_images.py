"""Images out of a log: one file per frame named by its stamp, or one MP4 video.

Frames come from the log layer's frame decoding (``LogReader.frames``), so every encoding
camlog reads exports: raw images of any encoding (bayer and YUV as colour), JPEG / PNG
``CompressedImage``, H.264 / H.265 ``CompressedVideo``. 8-bit images go to PNG or JPEG;
16-bit images stay 16-bit in PNG, float depth becomes 16-bit millimetres. The
files are written into a hidden temporary folder and moved into place when every frame is
done; an MP4 (PyAV, the ``camlog[video]`` extra) is written under a temporary name too.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from replay import ReplayError, open_reader
from replay.atomic import AtomicFolder, AtomicOutput
from replay.frames import Color, Frame
from replay.selection import window_ns
from replay.storage import Location, local_paths
from replay.wire import FRAME_TYPES

from ..errors import InputError, UsageError
from ..requests.logs import ExportRequest

__all__ = ["EXPORT_FORMATS", "ExportResult", "export_images", "frame_file_name"]

#: --format -> file suffix
EXPORT_FORMATS = {"png": ".png", "jpg": ".jpg", "mp4": ".mp4"}
#: stamps are written with this many digits, so that names sort in time order
STAMP_DIGITS = 19


@dataclass(frozen=True, slots=True)
class ExportResult:
    """What an export wrote: the folder or video, frame count and the bytes on disk."""

    output: Path
    frames: int
    bytes_written: int
    fps: float | None = None


def frame_file_name(stamp_ns: int, suffix: str, repeat: int = 0) -> str:
    """``<stamp_ns, 19 digits>.png`` (``-1``, ``-2`` ... for repeated stamps).

    >>> frame_file_name(1_033_333_333, ".png")
    '0000000001033333333.png'
    """
    extra = f"-{repeat}" if repeat else ""
    return f"{stamp_ns:0{STAMP_DIGITS}d}{extra}{suffix}"


def _depth_mm(frame: Frame) -> np.ndarray:
    """Float depth as 16-bit millimetres (the ROS convention for depth PNG); no
    measurement (0, NaN, inf) stays 0."""
    metres = frame.pixels.astype(np.float64) * (frame.depth_unit_m or 1.0)
    metres = np.nan_to_num(metres, nan=0.0, posinf=0.0, neginf=0.0)
    return np.clip(np.round(metres * 1000.0), 0, 65535).astype(np.uint16)


#: colour order -> channel indices giving OpenCV's order (None: already BGR(A) or one channel)
_TO_OPENCV = {Color.RGB: [2, 1, 0], Color.RGBA: [2, 1, 0, 3]}


def _file_pixels(frame: Frame, fmt: str) -> np.ndarray:
    """Pixels as OpenCV writes them: BGR(A) for colour, one channel for mono and depth;
    16-bit stays 16-bit in PNG (float depth becomes millimetres)."""
    px = frame.pixels
    if frame.color is Color.DEPTH and px.dtype.kind == "f":
        px = _depth_mm(frame)
    elif px.dtype not in (np.uint8, np.uint16):
        px = frame.to8()
    if px.dtype != np.uint8 and fmt == "jpg":
        raise UsageError(f"JPEG cannot hold 16-bit images ({frame.source}): use --format png "
                         "(16-bit PNG)")
    if fmt == "jpg" and frame.color in (Color.RGBA, Color.BGRA):
        return frame.bgr8()
    order = _TO_OPENCV.get(frame.color)
    return np.ascontiguousarray(px[..., order]) if order else px


def _check_topic(reader: Any, topic: str) -> None:
    info = reader.topics.get(topic)
    if info is None or info.msgtype not in FRAME_TYPES:
        images = sorted(t.name for t in reader.topics.values() if t.msgtype in FRAME_TYPES)
        what = "no topic" if info is None else f"{info.msgtype} on"
        raise InputError(f"{reader.path} has {what} {topic} to export (image topics: "
                         f"{', '.join(images) or 'none'})")


def _frames(log: Location, topic: str, start_s: float | None, end_s: float | None, *,
            every: int, recover: bool) -> tuple[int, Iterator[Frame]]:
    """(how many frames will be exported, the decoded frames: every ``every``-th)."""
    reader = open_reader(log, recover=recover)
    try:
        _check_topic(reader, topic)
        start_ns, end_ns = window_ns(reader.start_ns, start_s, end_s)
        total = -(-reader.topics[topic].count // every)
    except BaseException:
        reader.close()
        raise

    def stream() -> Iterator[Frame]:
        with reader:
            for index, record in enumerate(reader.frames([topic], start_ns, end_ns)):
                if index % every == 0:
                    yield record.message

    return total, stream()


def export_images(request: ExportRequest) -> ExportResult:
    """Write the frames of ``topic`` as image files into ``output`` (or one MP4 there)."""
    log, topic, output, fmt = request.log, request.topic, request.output, request.file_format
    if topic is None:
        raise UsageError("name the image topic to export with --topic")
    every, start_s, end_s = request.every, request.start, request.end
    jpeg_quality, overwrite, recover = request.jpeg_quality, request.overwrite, request.recover
    progress = request.progress
    if fmt not in EXPORT_FORMATS:
        raise UsageError(f"unknown export format {fmt!r} (use {', '.join(EXPORT_FORMATS)})")
    if every < 1:
        raise UsageError(f"--every must be >= 1, got {every}")
    if fmt == "mp4":
        return _export_video(log, topic, output, every=every, start_s=start_s, end_s=end_s,
                             overwrite=overwrite, recover=recover, progress=progress)
    import cv2
    from tqdm import tqdm

    total, frames = _frames(log, topic, start_s, end_s, every=every, recover=recover)
    params = [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality] if fmt == "jpg" else []
    suffix = EXPORT_FORMATS[fmt]
    # the names are known only while reading: check the folder's own files against them
    # as they are written, then move them in together
    count = size = 0
    seen: dict[int, int] = {}
    try:
        with AtomicFolder(output, [], overwrite=overwrite, inputs=local_paths(log)) as folder:
            for frame in tqdm(frames, total=total, unit="frame", desc=f"export {topic}",
                              disable=not progress, leave=False):
                repeat = seen.get(frame.stamp_ns, 0)
                seen[frame.stamp_ns] = repeat + 1
                name = frame_file_name(frame.stamp_ns, suffix, repeat)
                if (output / name).exists() and not overwrite:
                    raise UsageError(f"{output} already holds {name} (pass --overwrite to "
                                     "replace it)")
                ok, buf = cv2.imencode(suffix, _file_pixels(frame, fmt), params)
                if not ok:
                    raise InputError(f"cannot encode a {frame.source} frame as {fmt}")
                (folder.path / name).write_bytes(buf.tobytes())
                count += 1
                size += len(buf)
            if not count:
                raise InputError(f"{log}: no frames of {topic} in the chosen window")
    except ReplayError as err:
        raise InputError(str(err)) from None
    return ExportResult(output, count, size)


def _median_fps(stamps_ns: list[int]) -> float:
    if len(stamps_ns) < 2:
        return 30.0
    period_ns = float(np.median(np.diff(np.asarray(stamps_ns, dtype=np.int64))))
    return 1e9 / period_ns if period_ns > 0 else 30.0


def _export_video(log: Location, topic: str, output: Path, *, every: int, start_s: float | None,
                  end_s: float | None, overwrite: bool, recover: bool,
                  progress: bool) -> ExportResult:
    """One H.264 MP4 at the median frame rate of the exported stamps (yuv420p)."""
    try:
        import av
    except ImportError:
        raise UsageError("--format mp4 needs PyAV: pip install 'camlog[video]'") from None
    from tqdm import tqdm

    if output.suffix.lower() != ".mp4":
        output = output / (topic.strip("/").replace("/", "_") + ".mp4")
        if output.parent.exists() and not output.parent.is_dir():
            raise UsageError(f"output {output.parent} exists and is not a directory")
        output.parent.mkdir(parents=True, exist_ok=True)
    # the frame rate comes from the stamps: read them first (no pixels decoded)
    with open_reader(log, recover=recover) as reader:
        _check_topic(reader, topic)
        start_ns, end_ns = window_ns(reader.start_ns, start_s, end_s)
        stamps = [raw.log_time_ns for raw in reader.raw_messages([topic], start_ns, end_ns)]
    fps = _median_fps(stamps[::every])
    total, frames = _frames(log, topic, start_s, end_s, every=every, recover=recover)
    count = 0
    try:
        with AtomicOutput(output, overwrite=overwrite, inputs=local_paths(log),
                          what="a video") as out:
            container = av.open(str(out.temp), mode="w", format="mp4")
            try:
                stream: Any = None
                for frame in tqdm(frames, total=total, unit="frame", desc=f"export {topic}",
                                  disable=not progress, leave=False):
                    rgb = frame.rgb8()
                    if stream is None:
                        stream = container.add_stream(
                            "libx264", rate=Fraction(fps).limit_denominator(1001))
                        # yuv420p needs even sides: a last odd row or column is dropped
                        stream.width, stream.height = rgb.shape[1] & ~1, rgb.shape[0] & ~1
                        stream.pix_fmt = "yuv420p"
                    rgb = rgb[:stream.height, :stream.width]
                    picture = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb),
                                                         format="rgb24")
                    for packet in stream.encode(picture):
                        container.mux(packet)
                    count += 1
                if stream is None:
                    raise InputError(f"{log}: no frames of {topic} in the chosen window")
                for packet in stream.encode():
                    container.mux(packet)
            finally:
                container.close()
    except ReplayError as err:
        raise InputError(str(err)) from None
    return ExportResult(output, count, output.stat().st_size, fps)
