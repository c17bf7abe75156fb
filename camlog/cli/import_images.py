"""``camlog import DIR -o LOG``: a folder of image files as a camera log."""

from __future__ import annotations

import argparse

from ..requests.arguments import request_from_args
from ..requests.logs import ImportRequest
from .args import add_request, print_warnings


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Register the ``import`` arguments."""
    add_request(p, ImportRequest)


def run(args: argparse.Namespace) -> int:
    """Call :func:`camlog.logs.importer.import_images`."""
    from camlog.logs.importer import import_images

    result = import_images(request_from_args(ImportRequest, args))
    print(f"imported {result.frames} frames per camera to {', '.join(result.topics)} in "
          f"{result.wall_s:.2f} s")
    print_warnings(f"{path} has no stereo partner; skipped" for path in result.skipped)
    print(f"wrote {result.output}")
    return 0
