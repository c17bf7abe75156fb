"""``camlog resync LOG -o OUT``: pair and re-stamp two unsynchronised cameras."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..requests.arguments import request_from_args
from ..requests.fields import RequestError
from ..requests.processing import ResyncRequest
from .args import add_request

if TYPE_CHECKING:
    from replay.records import TimeOffset


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``resync`` arguments."""
    add_request(p, ResyncRequest)


def _stamps(values: list[int]) -> str:
    shown = ", ".join(str(v) for v in values[:10])
    return f" [{shown}{', ...' if len(values) > 10 else ''}]" if values else ""


def offset_line(offset: TimeOffset) -> str:
    """A measured offset in one line: value ± sigma, frames, method."""
    return (f"time offset {offset.second} - {offset.first}: {offset.offset_ms:+.3f} ± "
            f"{offset.std_ms:.3f} ms (1 sigma; the right camera stamps an instant that much "
            f"later), from the {offset.method} in {offset.frames} moving frames of "
            f"{offset.frames_fitted}, RMS {offset.rms_px:.3f} px")


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.processing.resync_log.resync_log` (or, only measuring the offset,
    :func:`~camlog.processing.resync_log.measure_log_offset`) and print what it found."""
    from ..processing.resync_log import measure_log_offset, resync_log

    request = request_from_args(ResyncRequest, args)
    if request.output is None and not request.estimate_offset:
        raise RequestError(ResyncRequest, "give {output} (or only {estimate_offset})")
    if request.output is None:
        measured = measure_log_offset(request)
        print(offset_line(measured.offset))
        print(f"wrote {measured.offset_file} in {measured.wall_s:.2f} s")
        return 0
    result = resync_log(request)
    s = result.stats
    if s.time_offset is not None:
        print(offset_line(s.time_offset))
    if s.right_stamps_moved_ns is not None:
        print(f"right stamps moved by {s.right_stamps_moved_ns / 1e6:+.3f} ms before pairing")
    print(f"paired {s.pairs} of {s.left_frames} left / {s.right_frames} right frames "
          f"(slop {s.slop_ns / 1e6:.3f} ms, re-stamped with the later stamp)")
    for side, unpaired in (("left", s.left_unpaired_stamps_ns),
                           ("right", s.right_unpaired_stamps_ns)):
        print(f"unpaired {side}: {len(unpaired)}{_stamps(unpaired)}")
    offset = s.offset_right_minus_left_ns
    if offset is not None:
        print(f"offset right - left: min {offset.min / 1e6:.3f} ms, median "
              f"{offset.median / 1e6:.3f} ms, max {offset.max / 1e6:.3f} ms")
    if result.offset_file is not None:
        print(f"wrote {result.offset_file}")
    print(f"wrote {result.output} in {result.wall_s:.2f} s")
    return 0
