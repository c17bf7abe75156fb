"""camera_calibration's ``ost.txt`` INI layout ("oST version 5.0 parameters")."""

from __future__ import annotations

from .messages import CameraInfo


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
