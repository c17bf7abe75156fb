"""Image-processing throughput (red pixels + edges) against a copy-through baseline, in one run.

On one recorded log the benchmark measures, in frames of the processed topic per second:

* ``decode``: read the log and decode every frame of the topic, nothing else;
* ``copy``: ``camlog process`` with a null processor that emits messages of exactly the
  types and sizes the real processors emit (an rgb8 and a mono8 image, two points) made of
  the input's own bytes, without computing anything: reading, serializing, compressing and
  writing the same number of bytes, i.e. the I/O limit of the pipeline;
* ``process``: ``camlog process --red-pixels --edges``.

Targets: process >= 0.7 x copy and >= 300 frames/s at 640x480 on 2 cores.

    python -m benchmarks.process_fps [--frames N] [--resolution WxH] [--repeats R] [--log LOG]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from camlog.processing.process_log import process_log
from camlog.requests.processing import ProcessRequest
from processors.base import Output
from processors.red_pixels import CENTROID, COUNT, OUTPUT_VIDEO
from processors.registry import configure, spec_of
from processors.spec import Configured, ProcessorSpec
from replay import Image, PointStamped, open_reader

from .docs import add_write_docs
from .report import emit, write_summary_rows

TOPIC = "/stereo_camera/left/image_raw"


class NullProcessor:
    """The red-pixels + edges outputs, same types and sizes, from the input's own bytes."""

    def __call__(self, image: Image) -> list[Output]:
        flat = image.pixels.reshape(-1)
        gray = flat[: image.width * image.height].reshape(image.height, image.width)
        point = PointStamped(image.stamp_ns, image.frame_id, np.zeros(3))
        return [
            (OUTPUT_VIDEO, Image(image.stamp_ns, image.frame_id, "rgb8", image.pixels)),
            (CENTROID, point),
            (COUNT, point),
            ("edges", Image(image.stamp_ns, image.frame_id, "mono8", gray)),
        ]


#: the null processor declared with the outputs of red pixels and edges
NULL = Configured(ProcessorSpec(
    name="null", summary="red pixels + edges outputs without computing",
    implementation="benchmarks.process_fps:NullProcessor",
    outputs=spec_of("red_pixels").outputs + spec_of("edges").outputs))


def decode_fps(log: Path) -> float:
    """Frames of the topic read and decoded per second."""
    started = time.perf_counter()
    frames = 0
    with open_reader(log) as reader:
        for raw in reader.raw_messages():
            if raw.topic == TOPIC:
                reader.decode(raw)
                frames += 1
    return frames / (time.perf_counter() - started)


def pipeline_fps(log: Path, out: Path, processors: list[Configured]) -> tuple[float, int]:
    """Frames per second of ``process_log`` and the output size in bytes."""
    result = process_log(ProcessRequest(log=log, output=out, topic=(TOPIC,),
                                        processors=tuple(processors), overwrite=True))
    return result.fps, out.stat().st_size


def record_log(path: Path, frames: int, resolution: tuple[int, int]) -> None:
    from recorder.record import record
    from recorder.scenario import load_scenario

    width, height = resolution
    scenario = load_scenario("red_block", {"frames": frames, "width": width, "height": height})
    record(scenario, path, overwrite=True, progress=False)


def run(log: Path, repeats: int, tmp: Path) -> dict[str, float]:
    """Best of ``repeats`` interleaved runs of each measurement."""
    decode, copy, process = [], [], []
    sizes = {}
    for _ in range(repeats):  # interleaved so that drifting machine load hits all three
        decode.append(decode_fps(log))
        fps, sizes["copy"] = pipeline_fps(log, tmp / "copy.mcap", [NULL])
        copy.append(fps)
        fps, sizes["process"] = pipeline_fps(log, tmp / "process.mcap",
                                          [configure("red_pixels"), configure("edges")])
        process.append(fps)
    return {"decode_fps": max(decode), "copy_fps": max(copy), "process_fps": max(process),
            "ratio": max(process) / max(copy), "copy_mb": sizes["copy"] / 1e6,
            "process_mb": sizes["process"] / 1e6}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--frames", type=int, default=300, help="frames per camera (300)")
    parser.add_argument("--resolution", default="640x480", help="WxH (640x480)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--log", type=Path, help="use this red_block-like log instead")
    args = parser.parse_args()
    width, height = (int(v) for v in args.resolution.split("x"))
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        log = args.log or tmp / "red_block.mcap"
        if args.log is None:
            record_log(log, args.frames, (width, height))
        r = run(log, args.repeats, tmp)
    print(f"log: {log.name if args.log else f'red_block {args.frames} frames {width}x{height}'}"
          f", topic {TOPIC}, best of {args.repeats}")
    print(f"decode only:            {r['decode_fps']:7.0f} frames/s")
    print(f"copy-through baseline:  {r['copy_fps']:7.0f} frames/s  ({r['copy_mb']:.1f} MB out)")
    print(f"red pixels + edges:     {r['process_fps']:7.0f} frames/s  ({r['process_mb']:.1f} MB "
          f"out)  = {r['ratio']:.2f} x copy-through (target >= 0.7, >= 300 frames/s)")
    emit("process red pixels + edges", baseline="copy-through", baseline_value=r["copy_fps"],
         measured="process", measured_value=r["process_fps"], unit="fps", ratio=r["ratio"],
         target=">= 0.7 and >= 300 fps")
    emit("process: decode only (reference)", baseline="decode only",
         baseline_value=r["decode_fps"], measured="process", measured_value=r["process_fps"],
         unit="fps", ratio=r["process_fps"] / r["decode_fps"], target="(reference)")
    write_summary_rows("process_fps", args)


if __name__ == "__main__":
    main()
