"""What ``camlog check`` can check in a log: its stereo pairs, its cameras that see a board,
and the cameras it cannot check (with why), each with the calibration it is measured with.

A stereo pair is two cameras under one namespace (``/rig/left``, ``/rig/right``) whose
calibrations say so: the right one's ``P[0, 3]`` is ``-fx * baseline``. ``--calibration``
gives the calibration instead of the log's camera_info: a ``camlog calibrate`` folder
(``left.yaml`` and ``right.yaml`` of a pair, with ``calibration.json``'s rotation standard
deviation; or ``ost.yaml``) or one YAML file, for the log's one pair or one camera.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from processors.calibration.board import Board
from replay.calibration_yaml import load_calibration
from replay.formats import LogReader
from replay.messages import CameraInfo

from ..errors import InputError, UsageError
from ..processing.cameras import CameraSource, cameras_in, find_camera, first_camera_info

__all__ = ["Checkable", "Unchecked", "checkable"]


@dataclass(frozen=True)
class Checkable:
    """Cameras measured together: a stereo pair (``kind`` ``stereo``, left then right) or
    one camera with a board in view (``board``), with their calibrations and the
    calibration's rotation uncertainty (degrees, 0 when it does not say)."""

    kind: str
    sources: tuple[CameraSource, ...]
    infos: tuple[CameraInfo, ...]
    rotation_std_deg: float = 0.0

    @property
    def name(self) -> str:
        """The camera the metrics are about: a pair's right camera (turned relative to the
        left), or the one camera."""
        return self.sources[-1].namespace


@dataclass(frozen=True)
class Unchecked:
    """A camera the log does not allow to check, and why."""

    namespace: str
    reason: str


def _given(calibration: Path) -> tuple[list[CameraInfo], float]:
    """The camera models of ``--calibration`` (one or a pair) and its rotation std (deg)."""
    if calibration.is_dir():
        files = [calibration / n for n in ("left.yaml", "right.yaml")]
        if not all(f.is_file() for f in files):
            files = [calibration / "ost.yaml"]
        if not files[0].is_file():
            raise InputError(f"{calibration}: no left.yaml and right.yaml, nor ost.yaml")
        std = 0.0
        summary = calibration / "calibration.json"
        if len(files) == 2 and summary.is_file():
            std = _rotation_std_deg(summary)
        return [load_calibration(f).camera_info for f in files], std
    return [load_calibration(calibration).camera_info], 0.0


def _rotation_std_deg(summary: Path) -> float:
    """The stereo rotation's standard deviation (degrees) a ``calibration.json`` gives."""
    try:
        stereo = json.loads(summary.read_text()).get("stereo") or {}
        return float(stereo.get("rotation_std_deg") or 0.0)
    except (ValueError, TypeError, AttributeError):
        raise InputError(f"{summary}: not a camlog calibration summary") from None


def _is_right(info: CameraInfo) -> bool:
    return abs(float(info.p[0, 3])) > 0.0


def checkable(reader: LogReader, *, cameras: list[str], board: Board | None,
              calibration: Path | None) -> tuple[list[Checkable], list[Unchecked]]:
    """The checks of a log's cameras (``cameras``: those named, default every one)."""
    sources = [find_camera(reader, c) for c in cameras] if cameras else \
        [find_camera(reader, topic) for _, topic in cameras_in(reader)]
    infos = {s.namespace: first_camera_info(reader, s) for s in sources}
    std = 0.0
    if calibration is not None:
        given, std = _given(calibration)
        if len(given) == 2:
            pairs = _pairs(sources, {ns: i for ns, i in infos.items() if i is not None})
            if len(pairs) != 1:
                raise UsageError(f"{reader.path}: --calibration {calibration} is a stereo pair "
                                 f"and the log has {len(pairs)} pairs: name them with --camera")
            infos[pairs[0][0].namespace], infos[pairs[0][1].namespace] = given
        elif len(sources) == 1:
            infos[sources[0].namespace] = given[0]
        else:
            raise UsageError(f"{reader.path}: --calibration {calibration} is one camera and the "
                             f"log has {len(sources)}: name it with --camera")
    known = {ns: i for ns, i in infos.items() if i is not None}
    checks: list[Checkable] = []
    paired: set[str] = set()
    for left, right in _pairs(sources, known):
        checks.append(Checkable("stereo", (left, right),
                                (known[left.namespace], known[right.namespace]), std))
        paired |= {left.namespace, right.namespace}
    unchecked: list[Unchecked] = []
    for source in sources:
        info = known.get(source.namespace)
        if info is None:
            unchecked.append(Unchecked(source.namespace, "no camera_info (give --calibration)"))
        elif board is not None:
            checks.append(Checkable("board", (source,), (info,)))
        elif source.namespace not in paired:
            unchecked.append(Unchecked(source.namespace, "a mono camera: no stereo partner "
                                       "and no board given (--size/--square)"))
    return checks, unchecked


def _pairs(sources: list[CameraSource], infos: dict[str, CameraInfo]
           ) -> list[tuple[CameraSource, CameraSource]]:
    """(left, right) of every two cameras under one namespace, one of them a right camera."""
    by_parent: dict[str, list[CameraSource]] = {}
    for source in sources:
        if source.namespace in infos:
            by_parent.setdefault(source.namespace.rpartition("/")[0], []).append(source)
    pairs = []
    for group in by_parent.values():
        if len(group) != 2:
            continue
        rights = [s for s in group if _is_right(infos[s.namespace])]
        if len(rights) == 1:
            left = next(s for s in group if s is not rights[0])
            pairs.append((left, rights[0]))
    return pairs
