"""camera_calibration's archives (``calibrationdata.tar.gz``) made for tests, as it writes them.

A rendered stereo rig (``stereo_checkerboard`` at 320x240, a new board pose every frame, as
the views camera_calibration keeps), its frames as PNG members, a calibration through camlog's
YAML writer, packed with ``tarfile``.
"""

from __future__ import annotations

import io
import tarfile
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest

from replay import CameraInfo, Image, open_reader
from replay.calibration_yaml import calibration_to_yaml
from replay.records.scenario import Scenario
from replay.topics import SCENARIO
from tests.slow import renders
from tests.workers import made_once

from .recordings import cli, held_for

SIDES = ("left", "right")


@dataclass(frozen=True)
class Rendered:
    """A rendered rig's frames (rgb8, per camera), its cameras' camera_info (the true
    models) and the true ``right_from_left`` (4, 4)."""

    images: list[list[np.ndarray]]
    infos: list[CameraInfo]
    right_from_left: np.ndarray


def render_rig(folder: Path, frames: int) -> Rendered:
    """``frames`` frames of stereo_checkerboard, the board at a new pose in each."""
    log = folder / "stereo.mcap"
    cli("record", str(held_for(folder, "stereo_checkerboard", hold_s=0.03)), "--frames",
        str(frames), "--resolution", "320x240", "-o", str(log), "--no-progress")
    images: list[list[np.ndarray]] = [[], []]
    infos: list[CameraInfo] = []
    with open_reader(log) as reader:
        for side, camera in enumerate(SIDES):
            for record in reader.messages([f"/stereo_camera/{camera}/image_raw"]):
                assert isinstance(record.message, Image)
                images[side].append(record.message.pixels)
            topic = f"/stereo_camera/{camera}/camera_info"
            info = next(r.message for r in reader.messages([topic]))
            assert isinstance(info, CameraInfo)
            infos.append(info)
        scenario = Scenario.from_message(next(r.message for r in reader.messages([SCENARIO])))
    left, right = (next(c for c in scenario.cameras if c.namespace.endswith(side))
                   for side in SIDES)
    right_from_left = np.linalg.inv(right.world_from_camera) @ left.world_from_camera
    return Rendered(images, infos, right_from_left)


@pytest.fixture(scope="session")
@renders
@made_once
def rendered_rig(tmp_path_factory: pytest.TempPathFactory) -> Rendered:
    """16 frames of a rendered rig (see :func:`render_rig`), once per session."""
    return render_rig(tmp_path_factory.mktemp("rendered_rig"), 16)


def png(pixels: np.ndarray) -> bytes:
    """PNG bytes of an rgb8 or mono8 image."""
    bgr = cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR) if pixels.ndim == 3 else pixels
    ok, data = cv2.imencode(".png", bgr)
    assert ok
    return data.tobytes()


def yaml(info: CameraInfo, name: str) -> bytes:
    """camera_info_manager YAML of a model (camlog's writer)."""
    return calibration_to_yaml(info, camera_name=name).encode()


def views(rendered: Rendered, *, sides: tuple[str, ...] = SIDES, folder: str = ""
          ) -> dict[str, bytes]:
    """The rig's frames as an archive's members (``left-0000.png`` ...)."""
    return {f"{folder}{side}-{i:04d}.png": png(rendered.images[s][i])
            for s, side in enumerate(sides) for i in range(len(rendered.images[s]))}


def pack(path: Path, members: dict[str, bytes]) -> Path:
    """A gzip-compressed tar file of ``members`` (name -> bytes), as camera_calibration's
    ``taradd`` writes them."""
    with tarfile.open(path, "w:gz") as archive:
        for name, data in members.items():
            entry = tarfile.TarInfo(name)
            entry.size = len(data)
            entry.uname = "calibrator"
            archive.addfile(entry, io.BytesIO(data))
    return path
