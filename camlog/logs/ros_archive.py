"""ROS camera_calibration's archive (``calibrationdata.tar.gz``), read as it is.

camera_calibration's *save* writes the views it kept and its result into one tar file
(gzip-compressed): ``left-0000.png``, ``left-0001.png``, ... for one camera; for a pair also
``right-0000.png``, ... (the same number for the two images of a pair); and its calibration as
``ost.yaml`` (one camera) or ``left.yaml`` and ``right.yaml`` (a pair), camera_info_manager
YAML, with ``ost.txt`` (the same in its INI layout; the only calibration older versions wrote).
Images may be PNG or PGM, colour or grey, and members may sit in a folder of the archive.
"""

from __future__ import annotations

import re
import tarfile
import zlib
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from replay.calibration_ini import cameras_from_ost
from replay.calibration_yaml import CalibrationFileError, calibration_from_yaml
from replay.errors import ImageFolderError
from replay.messages import CameraInfo

__all__ = ["RosArchive", "is_ros_archive", "read_ros_archive"]

#: an image of the archive: side, number, extension
_IMAGE = re.compile(r"(left|right)-?(\d+)\.(png|pgm|ppm|jpe?g)", re.IGNORECASE)


@dataclass(frozen=True)
class RosArchive:
    """An archive's images and calibration: ``frames`` holds per view its image member's
    name, left then right for a pair, in number order; ``images`` every image's encoded
    bytes by member name; ``calibration`` the archive's own camera models (left, right),
    empty when it has none, each read from the member ``calibration_files`` names."""

    path: Path
    frames: list[tuple[str, ...]]
    images: dict[str, bytes]
    calibration: list[CameraInfo]
    calibration_files: list[str]

    @property
    def stereo(self) -> bool:
        """Whether the archive holds a pair's views."""
        return len(self.frames[0]) == 2


def is_ros_archive(path: Path) -> bool:
    """Whether ``path`` is a file named as a tar archive (``.tar.gz``, ``.tgz``, ``.tar``)."""
    name = path.name.lower()
    return path.is_file() and name.endswith((".tar.gz", ".tgz", ".tar"))


def _read_members(path: Path) -> dict[str, bytes]:
    """Every regular file of the archive by its name, read in one pass."""
    try:
        with tarfile.open(path, "r:*") as archive:
            members = {}
            for member in archive:
                if member.isfile():
                    handle = archive.extractfile(member)
                    if handle is not None:
                        members[member.name] = handle.read()
            return members
    except (tarfile.TarError, EOFError, OSError, zlib.error) as err:
        reason = str(err).strip() or type(err).__name__
        raise ImageFolderError(f"{path}: not a readable tar archive ({reason})") from None


def _frames(path: Path, members: dict[str, bytes]) -> list[tuple[str, ...]]:
    """Image members per view: ``(left,)`` or ``(left, right)``, in number order."""
    sides: dict[str, dict[int, str]] = {"left": {}, "right": {}}
    for name in members:
        found = _IMAGE.fullmatch(PurePosixPath(name).name)
        if found is not None:
            sides[found.group(1).lower()][int(found.group(2))] = name
    left, right = sides["left"], sides["right"]
    if not left:
        raise ImageFolderError(f"{path}: no left-NNNN.png images (not a camera_calibration "
                               f"archive? it holds {len(members)} files)")
    if not right:
        return [(left[n],) for n in sorted(left)]
    if left.keys() != right.keys():
        alone = sorted(left.keys() ^ right.keys())
        first = left.get(alone[0]) or right[alone[0]]
        raise ImageFolderError(
            f"{path}: {len(left)} left and {len(right)} right images, and "
            f"{PurePosixPath(first).name} has no partner: a stereo archive pairs "
            "left-NNNN with right-NNNN")
    return [(left[n], right[n]) for n in sorted(left)]


def _by_name(members: dict[str, bytes]) -> dict[str, str]:
    """Base name -> member name (the first member of each base name)."""
    out: dict[str, str] = {}
    for name in members:
        out.setdefault(PurePosixPath(name).name, name)
    return out


def _calibration(path: Path, members: dict[str, bytes], stereo: bool
                 ) -> tuple[list[CameraInfo], list[str]]:
    """The archive's own calibration (YAML first, then ``ost.txt``) and where it was read;
    none when the archive holds neither."""
    named = _by_name(members)
    wanted = ["left.yaml", "right.yaml"] if stereo else ["ost.yaml"]
    if all(n in named for n in wanted):
        infos = []
        for file in wanted:
            try:
                infos.append(calibration_from_yaml(
                    members[named[file]].decode("utf-8", errors="replace")).camera_info)
            except (CalibrationFileError, ValueError) as err:
                raise ImageFolderError(f"{path}: {named[file]}: {err}") from None
        return infos, [named[file] for file in wanted]
    if "ost.txt" not in named:
        return [], []
    try:
        cameras = cameras_from_ost(members[named["ost.txt"]].decode("utf-8", errors="replace"))
    except CalibrationFileError as err:
        raise ImageFolderError(f"{path}: {named['ost.txt']}: {err}") from None
    if len(cameras) != (2 if stereo else 1):
        raise ImageFolderError(
            f"{path}: {named['ost.txt']} holds {len(cameras)} cameras "
            f"({', '.join(n for n, _ in cameras)}) for {'a pair' if stereo else 'one camera'}'s "
            "images")
    return [info for _, info in cameras], [named["ost.txt"]] * len(cameras)


def read_ros_archive(path: Path) -> RosArchive:
    """The archive at ``path``; one :class:`~replay.errors.ImageFolderError` line for an
    archive that does not read, holds no views, pairs left and right images unevenly, or
    whose calibration does not read."""
    members = _read_members(path)
    frames = _frames(path, members)
    calibration, files = _calibration(path, members, len(frames[0]) == 2)
    images = {name: members[name] for frame in frames for name in frame}
    return RosArchive(path, frames, images, calibration, files)
