"""``camlog export LOG --topic T -o DIR [--format png|jpg|mp4]``: images out of a log.

Like ``image_view``'s ``extract_images``: one file per frame named by its header stamp
(``<stamp_ns>.png``, 19 digits so names sort in time order), 16-bit images (depth) as 16-bit
PNG, or one H.264 MP4 with ``--format mp4`` (PyAV: ``pip install 'camlog[video]'``).
"""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.logs import ExportRequest
from .args import add_request


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``export`` arguments."""
    add_request(p, ExportRequest)


def run(args: argparse.Namespace) -> int:
    """Export the frames and say where they went."""
    from ..processing.export_images import export_images

    request = request_from_args(ExportRequest, args)
    result = export_images(request)
    rate = f" at {result.fps:.2f} fps" if result.fps else ""
    print(f"exported {result.frames} frames of {request.topic}{rate} "
          f"({result.bytes_written / 1e6:.1f} MB)")
    print(f"wrote {result.output}")
    return 0
