"""Boards held still: consecutive frames that show one pose become one averaged view.

A held board gives many frames of one pose. Their corners differ only by the part of the
detection error that changes from frame to frame (sensor noise); the rest — the detector's
sub-pixel bias at that pose — is the same in all of them. Treating the frames as independent
views would count that shared error once per frame and claim an uncertainty several times
too small. So the frames of a hold are averaged into one view; the average keeps all the
evidence (its frame-to-frame noise shrinks as 1/sqrt(n)) and the shared part is what the
solver's residuals then measure. The frame-to-frame scatter is reported: it says how much a
repeated frame can add.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from replay.messages import F64

I64 = npt.NDArray[np.int64]
#: a frame belongs to a hold when no corner moved more than this from the hold's first frame
HOLD_TOLERANCE_PX = 0.25


@dataclass(frozen=True)
class Seen:
    """What one camera saw at one instant: corners ``(M, 2)`` of board points ``(M,)``."""

    point_ids: I64
    corners_px: F64


@dataclass(frozen=True)
class Hold:
    """Instants ``members`` that show the board at one pose, and per camera the mean of its
    corners over them."""

    members: list[int]
    mean: dict[int, Seen]


def _still(a: Seen, b: Seen, tolerance_px: float) -> bool:
    return (a.point_ids.shape == b.point_ids.shape and bool(np.all(a.point_ids == b.point_ids))
            and float(np.abs(a.corners_px - b.corners_px).max(initial=0.0)) <= tolerance_px)


def holds(instants: list[dict[int, Seen]], *,
          tolerance_px: float = HOLD_TOLERANCE_PX) -> list[Hold]:
    """Group consecutive instants (each: camera -> what it saw) whose cameras all saw the
    same points within ``tolerance_px`` of the group's first instant; every instant lands in
    exactly one hold, in order."""
    out: list[Hold] = []
    start = 0
    for i in range(1, len(instants) + 1):
        first = instants[start]
        if i < len(instants) and instants[i].keys() == first.keys() and all(
                _still(first[c], instants[i][c], tolerance_px) for c in first):
            continue
        members = list(range(start, i))
        mean = {c: Seen(first[c].point_ids,
                        np.mean([instants[m][c].corners_px for m in members], axis=0))
                for c in first}
        out.append(Hold(members, mean))
        start = i
    return out


def frame_scatter_px(instants: list[dict[int, Seen]], groups: list[Hold]) -> float | None:
    """RMS per coordinate of the corners of held frames about their hold's mean (px): the
    frame-to-frame part of the detection error. None without a hold of two frames."""
    squares, dof = 0.0, 0
    for hold in groups:
        n = len(hold.members)
        if n < 2:
            continue
        for camera, mean in hold.mean.items():
            deviations = np.stack([instants[m][camera].corners_px for m in hold.members]) \
                - mean.corners_px
            squares += float(np.sum(deviations ** 2))
            dof += (n - 1) * mean.corners_px.size
    return math.sqrt(squares / dof) if dof else None
