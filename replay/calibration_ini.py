"""camera_calibration's ``ost.txt`` INI layout ("oST version 5.0 parameters"): written by
:func:`ost_text`, read by :func:`cameras_from_ost`.

The text is a run of sections: ``[image]`` gives ``width`` and ``height`` of the cameras after
it, every other section (``[narrow_stereo]``, ``[narrow_stereo/left]``, ...) one camera as
``camera matrix`` (3 rows), ``distortion`` (1 row), ``rectification`` (3 rows) and
``projection`` (3 rows), each key on a line of its own followed by its rows. A stereo pair is
two sections (camera_calibration repeats the header and ``[image]`` before the second).
"""

from __future__ import annotations

import numpy as np

from .calibration_yaml import CalibrationFileError
from .messages import CameraInfo

#: the distortion model of a section, told by how many coefficients it has
_MODELS = {4: "equidistant", 5: "plumb_bob", 8: "rational_polynomial"}
#: key -> rows of its matrix (None: one row of any length)
_KEYS = {"camera matrix": 3, "distortion": None, "rectification": 3, "projection": 3}


def _rows(values: object, cols: int) -> str:
    import numpy as np

    array = np.asarray(values, dtype=np.float64).reshape(-1, cols)
    return "\n".join(" ".join(f"{v:.6f}" for v in row) for row in array)


def _section(name: str, info: CameraInfo) -> str:
    return (
        f"[{name}]\n\n"
        f"camera matrix\n{_rows(info.k, 3)}\n\n"
        f"distortion\n{_rows(info.d, max(1, info.d.size))}\n\n"
        f"rectification\n{_rows(info.r, 3)}\n\n"
        f"projection\n{_rows(info.p, 4)}\n\n"
    )


def ost_text(mono: CameraInfo | None = None, *, left: CameraInfo | None = None,
             right: CameraInfo | None = None) -> str:
    """INI text for one camera (``[narrow_stereo]``) or a stereo pair (``/left``, ``/right``)."""
    first = mono or left
    if first is None:
        raise ValueError("give a mono camera or a left and right camera")
    head = (f"# oST version 5.0 parameters\n\n\n[image]\n\nwidth\n{first.width}\n\n"
            f"height\n{first.height}\n\n")
    if mono is not None:
        return head + _section("narrow_stereo", mono)
    if left is None or right is None:
        raise ValueError("stereo needs both left and right")
    return head + _section("narrow_stereo/left", left) + _section("narrow_stereo/right", right)


def _numbers(lines: list[str], where: str) -> np.ndarray:
    try:
        return np.array([[float(v) for v in line.split()] for line in lines], dtype=np.float64)
    except ValueError:
        raise CalibrationFileError(f"{where}: expected rows of numbers") from None


def cameras_from_ost(text: str) -> list[tuple[str, CameraInfo]]:
    """Every camera section of ``ost.txt`` text as (section name, camera model), in order;
    :class:`~replay.calibration_yaml.CalibrationFileError` names what is missing or
    malformed."""
    sections: list[tuple[str, dict[str, list[str]]]] = []
    key: str | None = None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line.startswith("#"):
            key = None
        elif line.startswith("[") and line.endswith("]"):
            sections.append((line[1:-1], {}))
            key = None
        elif not sections:
            raise CalibrationFileError(f"'{line}' before the first [section]")
        elif key is None:
            key = line
            sections[-1][1][key] = []
        else:
            sections[-1][1][key].append(line)
    width = height = 0
    cameras: list[tuple[str, CameraInfo]] = []
    for name, values in sections:
        if name == "image":
            try:
                width, height = (int(values[k][0]) for k in ("width", "height"))
            except (KeyError, IndexError, ValueError):
                raise CalibrationFileError("[image]: expected width and height") from None
            continue
        missing = [k for k in _KEYS if k not in values]
        if missing:
            raise CalibrationFileError(f"[{name}]: missing {', '.join(missing)}")
        k, d, r, p = (_numbers(values[key], f"[{name}] {key}") for key in _KEYS)
        shapes = {"camera matrix": (k, (3, 3)), "rectification": (r, (3, 3)),
                  "projection": (p, (3, 4))}
        for key, (matrix, shape) in shapes.items():
            if matrix.shape != shape:
                raise CalibrationFileError(f"[{name}] {key}: expected {shape[0]}x{shape[1]} "
                                           f"values, got {matrix.size}")
        coefficients = d.reshape(-1)
        if not width or not height:
            raise CalibrationFileError(f"[{name}]: no [image] width and height before it")
        model = _MODELS.get(coefficients.size, "plumb_bob")
        cameras.append((name, CameraInfo(0, "", width, height, model, coefficients, k, r, p)))
    if not cameras:
        raise CalibrationFileError("no camera section")
    return cameras
