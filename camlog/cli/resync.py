"""``camlog resync LOG -o OUT``: pair and re-stamp two unsynchronised cameras."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.processing import ResyncRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``resync`` arguments."""
    add_request(p, ResyncRequest)


def _stamps(values: list[int]) -> str:
    shown = ", ".join(str(v) for v in values[:10])
    return f" [{shown}{', ...' if len(values) > 10 else ''}]" if values else ""


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.processing.resync_log.resync_log` and print its pairing
    statistics."""
    from ..processing.resync_log import resync_log

    result = resync_log(request_from_args(ResyncRequest, args))
    s = result.stats
    print(f"paired {s.pairs} of {s.left_frames} left / {s.right_frames} right frames "
          f"(slop {s.slop_ns / 1e6:.3f} ms, re-stamped with the later stamp)")
    for side, unpaired in (("left", s.left_unpaired_stamps_ns),
                           ("right", s.right_unpaired_stamps_ns)):
        print(f"unpaired {side}: {len(unpaired)}{_stamps(unpaired)}")
    offset = s.offset_right_minus_left_ns
    if offset is not None:
        print(f"offset right - left: min {offset.min / 1e6:.3f} ms, median "
              f"{offset.median / 1e6:.3f} ms, max {offset.max / 1e6:.3f} ms")
    print(f"wrote {result.output} in {result.wall_s:.2f} s")
    return 0
