"""``camlog import``: a folder of image files as a camera log (like Kalibr's bag creator), or
ROS camera_calibration's archive (``calibrationdata.tar.gz``, :mod:`.ros_archive`) as it is.

Files (PNG, JPEG, PPM/PGM/PNM; 8- or 16-bit; colour or grey, told by content, not by
extension) are taken in natural sort order (``img2`` before ``img10``) and stamped
``start + i / rate``. Stereo folders pair ``left*`` and ``right*`` files by the rest of their
name (``left0003.pgm`` with ``right0003.pgm``) and give both images of a pair one stamp.
Colour images are stored ``rgb8``, grey ones ``mono8`` or ``mono16``. An archive's views are
taken in number order (a pair's two images under one stamp) and its own calibration becomes the
log's camera_info (unless ``--camera-info`` gives one).
"""

from __future__ import annotations

import re
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

from replay.calibration_yaml import load_calibration
from replay.errors import ImageFolderError, OptionError
from replay.formats import open_writer
from replay.messages import CameraInfo, Image
from replay.topics import camera_of

from ..requests.logs import ImportRequest
from .ros_archive import RosArchive, is_ros_archive, read_ros_archive

__all__ = [
    "EXTENSIONS",
    "RAW_IMAGE_SUFFIXES",
    "ImportResult",
    "decode_image",
    "frame_id_for",
    "image_files",
    "import_images",
    "import_topic",
    "natural_key",
    "pair_image_files",
    "read_image",
    "stamps_ns",
]

EXTENSIONS = (".png", ".jpg", ".jpeg", ".ppm", ".pgm", ".pnm")
SIDES = ("left", "right")


def natural_key(name: str) -> tuple[tuple[int, int | str], ...]:
    """Sort key that orders digit runs by value: ``img2`` < ``img10``.

    >>> sorted(["img10.png", "img2.png", "img1.png"], key=natural_key)
    ['img1.png', 'img2.png', 'img10.png']
    """
    return tuple((0, int(part)) if part.isdigit() else (1, part.lower())
                 for part in re.split(r"(\d+)", name) if part)


def image_files(folder: Path) -> list[Path]:
    """Image files directly in ``folder``, natural order; errors for missing/empty folders."""
    if not folder.exists():
        raise ImageFolderError(f"{folder} does not exist")
    if not folder.is_dir():
        raise ImageFolderError(f"{folder} is not a folder")
    files = [p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in EXTENSIONS]
    if not files:
        raise ImageFolderError(f"{folder} has no image files ({', '.join(EXTENSIONS)})")
    return sorted(files, key=lambda p: natural_key(p.name))


def pair_image_files(files: Sequence[Path]) -> tuple[list[tuple[Path, Path]], list[Path]]:
    """``(left, right)`` pairs matched by the name after ``left``/``right`` (extension
    ignored), in natural order, and the files that found no partner.

    >>> pairs, alone = pair_image_files([Path("left1.png"), Path("right1.png"), Path("left2.png")])
    >>> [(a.name, b.name) for a, b in pairs], [p.name for p in alone]
    ([('left1.png', 'right1.png')], ['left2.png'])
    """
    sides: dict[str, dict[str, Path]] = {side: {} for side in SIDES}
    alone: list[Path] = []
    for path in files:
        stem = path.stem.lower()
        side = next((s for s in SIDES if stem.startswith(s)), None)
        if side is None or stem[len(side):] in sides[side]:
            alone.append(path)
            continue
        sides[side][stem[len(side):]] = path
    left, right = sides["left"], sides["right"]
    keys = sorted(set(left) & set(right), key=natural_key)
    alone += [p for k, p in (*left.items(), *right.items()) if k not in keys]
    return [(left[k], right[k]) for k in keys], sorted(alone, key=lambda p: natural_key(p.name))


def stamps_ns(count: int, *, start_ns: int, rate_hz: float) -> list[int]:
    """``start + round(i * 1e9 / rate)`` for ``i < count``.

    >>> stamps_ns(3, start_ns=0, rate_hz=4.0)
    [0, 250000000, 500000000]
    """
    if not (rate_hz > 0 and np.isfinite(rate_hz)):
        raise OptionError(f"--rate must be > 0 Hz, got {rate_hz}")
    if start_ns < 0:
        raise OptionError(f"--start-time must be >= 0 ns, got {start_ns}")
    return [start_ns + round(i * 1e9 / rate_hz) for i in range(count)]


def frame_id_for(namespace: str) -> str:
    """``/stereo/left`` -> ``stereo_left_optical_frame``."""
    return "_".join(p for p in namespace.split("/") if p) + "_optical_frame"


def read_image(path: Path, *, stamp_ns: int, frame_id: str) -> Image:
    """One file as an Image: ``rgb8`` (colour, alpha dropped), ``mono8`` or ``mono16``."""
    try:
        data = path.read_bytes()
    except OSError as err:
        raise ImageFolderError(f"{path}: {err.strerror or err}") from None
    return decode_image(data, where=str(path), stamp_ns=stamp_ns, frame_id=frame_id)


def decode_image(data: bytes, *, where: str, stamp_ns: int, frame_id: str) -> Image:
    """An encoded image file's bytes (``where`` names it in errors) as an Image, as
    :func:`read_image`."""
    try:
        array = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    except cv2.error:
        array = None
    if array is None:
        raise ImageFolderError(f"{where}: not a readable image file")
    if array.dtype not in (np.uint8, np.uint16):
        raise ImageFolderError(f"{where}: {array.dtype} pixels are not supported (8 or 16 bit)")
    if array.ndim == 3 and array.shape[2] == 1:
        array = array[:, :, 0]
    if array.ndim == 2:
        encoding = "mono16" if array.dtype == np.uint16 else "mono8"
        return Image(stamp_ns, frame_id, encoding, array)
    if array.dtype == np.uint16:
        raise ImageFolderError(f"{where}: 16-bit colour images are not supported")
    code = cv2.COLOR_BGRA2RGB if array.shape[2] == 4 else cv2.COLOR_BGR2RGB
    return Image(stamp_ns, frame_id, "rgb8", cv2.cvtColor(array, code))


@dataclass(frozen=True)
class ImportResult:
    """What :func:`import_images` wrote."""

    output: Path
    topics: list[str]
    frames: int  # images per camera
    skipped: list[Path] = field(default_factory=list)  # files without a stereo partner
    wall_s: float = 0.0


#: image topic names below a camera namespace that hold raw images (``sensor_msgs/Image``)
RAW_IMAGE_SUFFIXES = ("image_raw", "image_rect", "image")


def import_topic(camera: str) -> tuple[str, str]:
    """(namespace, image topic) an import writes for ``camera``: a namespace gets
    ``NS/image_raw``; a raw image topic's name (:data:`RAW_IMAGE_SUFFIXES`) is kept.

    >>> import_topic("/fisheye"), import_topic("/cam/image_raw/")
    (('/fisheye', '/fisheye/image_raw'), ('/cam', '/cam/image_raw'))
    """
    name = "/" + camera.strip("/")
    namespace = camera_of(name)
    if namespace is None:
        return name, f"{name.rstrip('/')}/image_raw"
    suffix = name.removeprefix(namespace).strip("/")
    if suffix not in RAW_IMAGE_SUFFIXES:
        raise OptionError(f"{name} is a topic for compressed images or video; import writes "
                          f"raw images: name the camera {namespace} (images on "
                          f"{namespace.rstrip('/')}/image_raw)")
    return namespace, name


def _camera_infos(paths: Sequence[Path], namespaces: Sequence[str]) -> list[CameraInfo | None]:
    if not paths:
        return [None] * len(namespaces)
    if len(paths) != len(namespaces):
        raise OptionError(f"give one --camera-info per camera ({len(namespaces)}), "
                          f"got {len(paths)}")
    return [load_calibration(path).camera_info for path in paths]


def import_images(request: ImportRequest) -> ImportResult:
    """Write the images of the request's ``folder`` to the log ``output`` (atomically).

    Mono: ``camera`` is a camera namespace (default ``/camera``) and the log gets
    ``{ns}/image_raw`` (+ ``{ns}/camera_info``); a name ending in a raw image topic's name
    (``/cam/image_raw``, ``/cam/image_rect``, ``/cam/image``) is that image topic. Stereo:
    ``camera`` is the rig's namespace (default ``/stereo``) and the log gets
    ``{ns}/left/image_raw`` and ``{ns}/right/image_raw`` (+ ``camera_info``).
    """
    folder, output, camera, rate_hz = request.folder, request.output, request.camera, \
        request.rate
    stereo, camera_info, start_ns = request.stereo, request.camera_info, request.start_time
    frame_id, fmt, overwrite, progress = (request.frame_id, request.format, request.overwrite,
                                          request.progress)
    started = time.perf_counter()
    archive = read_ros_archive(folder) if is_ros_archive(folder) else None
    skipped: list[Path] = []
    frames: list[tuple[Path, ...]]
    if archive is not None:
        if stereo and not archive.stereo:
            raise ImageFolderError(f"{folder}: --stereo, but the archive holds one camera's "
                                   "images (left-NNNN.png, no right-NNNN.png)")
        stereo = archive.stereo
        frames = [tuple(folder / name for name in frame) for frame in archive.frames]
    elif stereo:
        pairs, skipped = pair_image_files(image_files(folder))
        if not pairs:
            raise ImageFolderError(f"{folder}: no left*/right* file pairs with matching names")
        frames = list(pairs)
    else:
        frames = [(path,) for path in image_files(folder)]
    if stereo:
        ns = "/" + (camera or "/stereo").strip("/")
        if camera_of(ns) is not None:
            raise OptionError(f"with --stereo, --camera names the rig's namespace (e.g. "
                              f"{camera_of(ns)}), not an image topic: {ns}")
        namespaces = [f"{ns}/{side}" for side in SIDES]
        image_topics = [f"{n}/image_raw" for n in namespaces]
    else:
        namespace, image_topic = import_topic(camera or "/camera")
        namespaces, image_topics = [namespace], [image_topic]
    infos = _camera_infos(camera_info, namespaces)
    info_files = list(camera_info)
    if archive is not None and not camera_info and archive.calibration:
        # the archive's own calibration becomes the log's camera_info
        infos = list(archive.calibration)
        info_files = [folder / name for name in archive.calibration_files]
    if frame_id is None:
        frame_ids = [frame_id_for(n) for n in namespaces]
    else:
        frame_ids = [f"{frame_id}_{side}" for side in SIDES] if stereo else [frame_id]
    stamps = stamps_ns(len(frames), start_ns=start_ns, rate_hz=rate_hz)
    sizes: list[tuple[int, int] | None] = [None] * len(namespaces)
    with open_writer(output, fmt=fmt, overwrite=overwrite, inputs=[folder]) as writer, \
            tqdm(total=len(frames), unit="frame", desc="import", leave=False,
                 disable=None if progress is None else not progress) as bar:
        for stamp, group in zip(stamps, frames, strict=True):
            for index, path in enumerate(group):
                image = _image(path, archive, stamp_ns=stamp, frame_id=frame_ids[index])
                size = (image.width, image.height)
                if sizes[index] is None:
                    sizes[index] = size
                    _check_info(infos[index], size, info_files[index] if infos[index] else None)
                elif size != sizes[index]:
                    first = sizes[index]
                    assert first is not None
                    raise ImageFolderError(f"{path} is {size[0]}x{size[1]}, but the camera's "
                                           f"first image is {first[0]}x{first[1]}")
                writer.write(image_topics[index], image)
                info = infos[index]
                if info is not None:
                    writer.write(f"{namespaces[index]}/camera_info", CameraInfo(
                        stamp, frame_ids[index], info.width, info.height, info.distortion_model,
                        info.d, info.k, info.r, info.p))
            bar.update()
    topics = image_topics + [f"{n}/camera_info" for n, i in zip(namespaces, infos, strict=True)
                             if i is not None]
    return ImportResult(output, topics, len(frames), skipped, time.perf_counter() - started)


def _image(path: Path, archive: RosArchive | None, *, stamp_ns: int, frame_id: str) -> Image:
    """The image file ``path``, or the archive's member ``path`` stands for (the archive's
    path joined with the member's name)."""
    if archive is None:
        return read_image(path, stamp_ns=stamp_ns, frame_id=frame_id)
    name = path.relative_to(archive.path).as_posix()
    return decode_image(archive.images[name], where=f"{archive.path}: {name}",
                        stamp_ns=stamp_ns, frame_id=frame_id)


def _check_info(info: CameraInfo | None, size: tuple[int, int], path: Path | None) -> None:
    if info is not None and (info.width, info.height) != size:
        raise OptionError(f"{path} is for {info.width}x{info.height} images, but the images "
                          f"are {size[0]}x{size[1]}")
