"""``camlog export LOG --topic T -o DIR [--format png|jpg|mp4]``: images out of a log;
``camlog export REC.rrd --calibration -o DIR``: camera models out of a rerun recording.

Like ``image_view``'s ``extract_images``: one file per frame named by its header stamp
(``<stamp_ns>.png``, 19 digits so names sort in time order), 16-bit images (depth) as 16-bit
PNG, or one H.264 MP4 with ``--format mp4`` (PyAV: ``pip install 'camlog[video]'``). With
``--calibration``, one camera_info YAML file per camera of a recording ``camlog view`` wrote.
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
    """Export the frames (or the camera models) and say where they went."""
    request = request_from_args(ExportRequest, args)
    if request.calibration:
        return _calibration(request)
    from ..processing.export_images import export_images

    result = export_images(request)
    rate = f" at {result.fps:.2f} fps" if result.fps else ""
    print(f"exported {result.frames} frames of {request.topic}{rate} "
          f"({result.bytes_written / 1e6:.1f} MB)")
    print(f"wrote {result.output}")
    return 0


def _calibration(request: ExportRequest) -> int:
    from ..processing.export_calibration import export_calibration

    result = export_calibration(request)
    for camera in result.cameras:
        changed = f" (the last of {camera.models} models it logged)" if camera.models > 1 \
            else ""
        print(f"{camera.entity}: {camera.path}{changed}")
    print(f"wrote {len(result.cameras)} calibration files into {result.output}")
    return 0
