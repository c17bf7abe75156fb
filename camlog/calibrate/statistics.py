"""What each camera's solution says of its own accuracy: projection uncertainty and
cross-validation.

The projection uncertainty (at the working range and far away) and the halves'
cross-validation are most of the solving work, and only the summary and the figures read
them. They are computed when the flow asks for them (:func:`camera_statistics`), from the
solution alone: the flow may compute them beside the evidence pass, which does not need them,
and joins them before the summary (:mod:`.flow`). That pays on short logs, where they are a
large share of the run; on a long log the pass and its writer thread already keep the cores
busy, and the statistics computed beside them only add their memory to the pass's (a 400 s
stereo log: a peak of 184 MB against 150 MB, in the same time): there they are computed
after it (:func:`beside_the_pass`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

from processors.calibration.uncertainty import (
    UncertaintyMap,
    projection_uncertainty,
    with_left_out,
)
from processors.calibration.validation import (
    CrossValidation,
    cross_validate,
    projection_difference,
)
from replay.messages import F64

from .solving import RigSolution

#: "far away": the uncertainty and cross-validation of rays
FAR_M = 1e4
#: the statistics run beside the evidence pass only for views of at most this many corners in
#: all (a 40 s stereo log of 8 poses repeated holds 6 700, 400 s 67 000; a board waved for
#: 40 s, 45 000, whose pass mostly waits for its writer)
BESIDE_CORNERS = 50_000

__all__ = ["BESIDE_CORNERS", "FAR_M", "CameraStatistics", "beside_the_pass",
           "camera_statistics"]


@dataclass(frozen=True)
class CameraStatistics:
    """What a camera's solution says of its own accuracy: the uncertainty of its
    projections (at the working range and far away) and the halves' cross-validation
    (None when the halves cannot be solved)."""

    uncertainty: UncertaintyMap
    rays_uncertainty: UncertaintyMap
    cross_validation: CrossValidation | None
    #: ``(rows, cols)`` at the maps' pixels: the projection difference of the model from the
    #: one with the terms its tangential test left out, included in both maps (None: none left
    #: out)
    left_out_px: F64 | None = None

    @property
    def cross_validation_px(self) -> float | None:
        """Expected worst error of the calibration (rays) from the halves' cross-validation."""
        return None if self.cross_validation is None else self.cross_validation.worst_px


def beside_the_pass(solved: RigSolution) -> bool:
    """Whether the statistics of ``solved`` are worth computing beside the evidence pass
    (views of at most :data:`BESIDE_CORNERS` corners)."""
    return sum(len(v.point_ids) for v in solved.rig.views) <= BESIDE_CORNERS


def camera_statistics(solved: RigSolution, *, points_in_board: F64) -> list[CameraStatistics]:
    """Each camera's statistics, in camera order, from the joint solve of the board points
    ``points_in_board`` ``(N, 3)``: the halves' cross-validation on a thread while the
    uncertainty maps are computed, joined here (their error raised here)."""
    joint = solved.joint
    sizes = [c.views.size for c in solved.cameras]
    # the halves' two solves on a thread of their own while the maps are computed here (both
    # mostly in numpy and OpenCV, which release the GIL); joined, their error raised, below.
    # The views at the instants they were solved with: one not simultaneous with its
    # instant's other views has a board pose of its own in each half too
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="camlog-halves") as pool:
        halves = pool.submit(
            cross_validate, points_in_board, joint.views, sizes, joint.options,
            range_m=FAR_M,
            disc_diameter_m=solved.circles.diameter_m if solved.circles is not None else None)
        maps = [(projection_uncertainty(joint.problem, index),
                 projection_uncertainty(joint.problem, index, range_m=FAR_M))
                for index in range(len(sizes))]
    validation = halves.result()
    out = []
    for index, (near, far) in enumerate(maps):
        richer = joint.left_out_models[index] if joint.left_out_models else None
        if richer is None:
            out.append(CameraStatistics(
                near, far, validation[index] if validation is not None else None))
            continue
        left_out = projection_difference(joint.models[index], richer, near.pixels)
        out.append(CameraStatistics(
            with_left_out(near, left_out), with_left_out(far, left_out),
            validation[index] if validation is not None else None, left_out))
    return out
