"""How much ``convert --compress h264`` shrinks a stereo log with sensor noise, and the
quality it keeps, against the raw log in the same run.

The baseline is the log ``camlog record`` writes (``stereo_checkerboard`` at 640x480 with
Gaussian sensor noise, rgb8 in zstd-compressed MCAP chunks). The figure is the size of
``camlog convert --compress h264`` of it, at the encoder's default settings (or ``--crf``),
and the mean PSNR of every picture against the raw frame it came from, as the convert
summary prints it. Target: more than ten times smaller at a PSNR of 38 dB or more.

    python -m benchmarks.video_size [--duration S] [--noise SIGMA] [--crf N [N ...]]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from camlog.cli import main as camlog
from camlog.logs.convert import convert_log
from camlog.requests.logs import ConvertRequest
from replay.frames.video import DEFAULT_CRF

from .docs import add_write_docs
from .report import emit, write_summary_rows

WIDTH, HEIGHT = 640, 480


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_write_docs(parser)
    parser.add_argument("--duration", type=float, default=10.0,
                        help="recording length in seconds (10; the claim is about 60)")
    parser.add_argument("--noise", type=float, default=2.0,
                        help="sensor noise, standard deviation in 8-bit levels (2)")
    parser.add_argument("--crf", type=int, nargs="+", default=[DEFAULT_CRF],
                        help=f"constant rate factors to measure (default {DEFAULT_CRF})")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        raw = Path(tmp) / "raw.mcap"
        started = time.perf_counter()
        assert camlog(["record", "stereo_checkerboard", "-o", str(raw), "--duration",
                       str(args.duration), "--resolution", f"{WIDTH}x{HEIGHT}", "--noise",
                       str(args.noise), "--no-progress"]) == 0
        record_s = time.perf_counter() - started
        raw_mb = raw.stat().st_size / 1e6
        print(f"raw log: {raw_mb:.1f} MB ({args.duration:g} s stereo {WIDTH}x{HEIGHT}, "
              f"noise {args.noise:g}; recorded in {record_s:.0f} s)")
        for crf in args.crf:
            out = Path(tmp) / f"h264_crf{crf}.mcap"
            started = time.perf_counter()
            result = convert_log(ConvertRequest(input=raw, output=out, compress="h264",
                                                crf=crf, progress=False))
            convert_s = time.perf_counter() - started
            video_mb = out.stat().st_size / 1e6
            images = result.reencoded
            psnr = min(result.psnr_db.values())
            per_topic = ", ".join(f"{t} {p:.1f} dB" for t, p in sorted(result.psnr_db.items()))
            print(f"h264 CRF {crf}: {video_mb:.2f} MB, {raw_mb / video_mb:.1f}x smaller than "
                  f"the raw log, {images * WIDTH * HEIGHT * 3 / 1e6 / video_mb:.0f}x smaller "
                  f"than the pixels; PSNR {per_topic}; {images} images in {convert_s:.0f} s")
            emit(f"convert --compress h264 CRF {crf}: {args.duration:g} s stereo "
                 f"{WIDTH}x{HEIGHT}, noise {args.noise:g}", baseline="raw MCAP (zstd)",
                 baseline_value=raw_mb, measured=f"h264 MCAP, PSNR {psnr:.1f} dB (worst topic)",
                 measured_value=video_mb, unit="MB", ratio=raw_mb / video_mb,
                 target="> 10x smaller at PSNR >= 38 dB")
    write_summary_rows("video_size", args)


if __name__ == "__main__":
    main()
