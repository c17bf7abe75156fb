"""A rig of cameras: every pair that saw the board at the same instants, and its figures.

The joint solve places every camera relative to the first (``camera_from_reference``); here
each pair of cameras that shares views gets its transform (``second_from_first``), baseline
and rotation with their standard deviations from the joint covariance, and the epipolar error
of its joint views after rectifying the pair (:func:`processors.calibration.stereo.
stereo_result`).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

from processors.calibration.joint import JointResult
from processors.calibration.stereo import StereoResult, stereo_result
from replay.messages import F64

from .instants import ViewsOfRig

__all__ = ["PairSolution", "rig_pairs"]


@dataclass(frozen=True)
class PairSolution:
    """Two cameras of a rig (indices ``first`` < ``second``): ``result.right_from_left`` is
    ``second_from_first``; ``result.pairs`` are the joint views used (view of ``first``,
    view of ``second``, as the rig's views are numbered)."""

    first: int
    second: int
    result: StereoResult


def _joint_views(rig: ViewsOfRig, first: int, second: int) -> list[tuple[int, int]]:
    """(view of ``first``, view of ``second``) at every instant both saw."""
    at: dict[int, dict[int, int]] = {}
    for index, view in enumerate(rig.views):
        at.setdefault(view.instant, {})[view.camera] = index
    return [(cameras[first], cameras[second]) for cameras in at.values()
            if {first, second} <= cameras.keys()]


def rig_pairs(joint: JointResult, rig: ViewsOfRig, *, points_in_board: F64,
              square_m: float) -> list[PairSolution]:
    """Every pair of cameras with views of the board at the same instants (and a joint view
    left after outliers), in camera order."""
    covariance: F64 | None = None
    out = []
    for first, second in combinations(range(len(joint.models)), 2):
        views = _joint_views(rig, first, second)
        usable = [p for p in views if p[0] not in joint.rejected and p[1] not in joint.rejected]
        if not usable:
            continue
        if covariance is None and first:
            covariance = joint.problem.global_covariance()
        result = stereo_result(joint, views, points_in_board=points_in_board,
                               square_m=square_m, cameras=(first, second),
                               global_covariance=covariance)
        out.append(PairSolution(first, second, result))
    return out
