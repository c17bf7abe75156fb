"""The full camera model in a recording, beside rerun's ``Pinhole``, and read back from it.

rerun's ``Pinhole`` holds ``K`` (as float32) and a resolution. Every camera entity also gets
a ``CameraInfo`` archetype (``rr.DynamicArchetype``: components rerun stores, shows in its
selection panel and returns from its dataframe API) holding the camera_info as the log gave
it, numbers as float64:

===================  ============================  =======================================
component            arrow type                    value
===================  ============================  =======================================
``distortion_model`` list<string>                  the lens model's name, as logged
``d``                list<double>                  D, in the model's order
``k``                list<double> (9)              K, row by row
``r``                list<double> (9)              R, row by row
``p``                list<double> (12)             P, row by row
``width``            list<uint32>                  image width (px)
``height``           list<uint32>                  image height (px)
``frame_id``         list<string>                  the optical frame
===================  ============================  =======================================

Each pinhole view of a distorted camera (:mod:`rerun_export.lens`) gets a ``PinholeView``
archetype beside its ``Pinhole``: ``view`` (its name), ``k`` (float64, row by row),
``width``, ``height``, ``rotation`` (the lens frame to the view's, row by row), ``fov_deg``
(across, top to bottom) and ``covered`` (the share of the raw image it shows).

:func:`recorded_cameras` reads the ``CameraInfo`` archetypes of an ``.rrd`` back, through
rerun's own loader, chunk by chunk (the images are never held).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import rerun as rr

from replay.messages import CameraInfo
from replay.pinhole_views import PinholeView

from .blueprint import LOG_TIME
from .errors import RerunExportError

__all__ = ["CAMERA_INFO", "PINHOLE_VIEW", "RecordedCamera", "camera_info_archetype",
           "pinhole_view_archetype", "recorded_cameras", "same_model"]

#: the archetype names
CAMERA_INFO = "CameraInfo"
PINHOLE_VIEW = "PinholeView"
#: the CameraInfo components, in the order of the table above
FIELDS = ("distortion_model", "d", "k", "r", "p", "width", "height", "frame_id")


def _f64(values: Any) -> np.ndarray:
    """A float64 copy (a decoded message's arrays may be unaligned views of its bytes,
    which arrow refuses)."""
    return np.array(values, dtype=np.float64).reshape(-1)


def camera_info_archetype(info: CameraInfo) -> rr.DynamicArchetype:
    """The ``CameraInfo`` archetype of a camera_info (see the module)."""
    return rr.DynamicArchetype(CAMERA_INFO, components={
        "distortion_model": [info.distortion_model], "d": _f64(info.d), "k": _f64(info.k),
        "r": _f64(info.r), "p": _f64(info.p), "width": np.array([info.width], np.uint32),
        "height": np.array([info.height], np.uint32), "frame_id": [info.frame_id]})


def pinhole_view_archetype(view: PinholeView) -> rr.DynamicArchetype:
    """The ``PinholeView`` archetype of a view (see the module)."""
    across, down = view.fov_rad
    return rr.DynamicArchetype(PINHOLE_VIEW, components={
        "view": [view.name], "k": _f64(view.k), "width": np.array([view.width], np.uint32),
        "height": np.array([view.height], np.uint32), "rotation": _f64(view.rotation),
        "fov_deg": np.array([math.degrees(across), math.degrees(down)]),
        "covered": np.array([view.covered])})


@dataclass(frozen=True)
class RecordedCamera:
    """A camera of a recording: its entity, the recording it is in, the camera_info last
    logged for it and how many different ones were logged."""

    recording_id: str
    entity: str
    info: CameraInfo
    models: int


def _info(row: dict[str, Any], where: str) -> CameraInfo:
    try:
        (model,), (width,), (height,), (frame_id,) = (row[n] for n in (
            "distortion_model", "width", "height", "frame_id"))
        k, r, p = (np.asarray(row[n], dtype=np.float64).reshape(3, -1) for n in "krp")
        d = np.asarray(row["d"], dtype=np.float64)
        if k.shape != (3, 3) or r.shape != (3, 3) or p.shape != (3, 4):
            raise ValueError("K, R or P has the wrong size")
    except (KeyError, TypeError, ValueError) as err:
        raise RerunExportError(f"{where}: a {CAMERA_INFO} that is not whole ({err})") from None
    return CameraInfo(0, str(frame_id), int(width), int(height), str(model), d, k, r, p)


def same_model(a: CameraInfo, b: CameraInfo) -> bool:
    """Whether two camera_infos describe the same camera model (stamp and frame aside)."""
    return (a.width, a.height, a.distortion_model) == (b.width, b.height, b.distortion_model) \
        and all(np.array_equal(x, y) for x, y in ((a.d, b.d), (a.k, b.k), (a.r, b.r),
                                                  (a.p, b.p)))


def _rows(path: Path) -> Iterator[tuple[str, str, int, dict[str, Any]]]:
    """(recording id, entity, log time in ns or -1 when static, components) of every
    ``CameraInfo`` row."""
    from rerun.chunk import RrdReader

    components = [f"{CAMERA_INFO}:{name}" for name in FIELDS]
    try:
        reader = RrdReader(path)
        recordings = reader.recordings()
    except Exception as err:  # rerun raises ValueError/OSError/RuntimeError from Rust
        raise RerunExportError(f"cannot read {path} as a rerun recording: {err}") from None
    for entry in recordings:
        for chunk in reader.stream(store=entry).filter(components=components).to_chunks():
            batch = chunk.to_record_batch()
            columns = {name.rpartition(":")[2]: batch.column(name).to_pylist()
                       for name in batch.schema.names
                       if name.rpartition(":")[0].endswith(CAMERA_INFO)}
            times = batch.column(LOG_TIME).cast(pa.int64()).to_pylist() \
                if LOG_TIME in batch.schema.names else [-1] * batch.num_rows
            for i in range(batch.num_rows):
                row = {name: values[i] for name, values in columns.items()}
                if any(value is not None for value in row.values()):
                    yield entry.recording_id, chunk.entity_path, times[i], row


def recorded_cameras(path: Path) -> list[RecordedCamera]:
    """Every camera of the ``.rrd`` at ``path`` with a ``CameraInfo``, in entity order per
    recording; :class:`~rerun_export.errors.RerunExportError` when it is not a readable
    recording."""
    rows: dict[tuple[str, str], list[tuple[int, CameraInfo]]] = {}
    for recording_id, entity, time_ns, row in _rows(path):
        rows.setdefault((recording_id, entity), []).append(
            (time_ns, _info(row, f"{path}: {entity}")))
    cameras = []
    for (recording_id, entity), timed in sorted(rows.items()):
        timed.sort(key=lambda pair: pair[0])
        models = 1 + sum(not same_model(a, b) for (_, a), (_, b) in pairwise(timed))
        cameras.append(RecordedCamera(recording_id, entity, timed[-1][1], models))
    return cameras
