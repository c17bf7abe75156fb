"""What each camera's solution says of its own accuracy, computed while the caller goes on.

The projection uncertainty (at the working range and far away) and the halves'
cross-validation are most of the solving work, and only the summary and the figures read
them: :func:`camera_statistics` can compute them on a thread of its own while the evidence
pass runs, and hands each camera a future of its statistics. That pays on short logs, where
they are a large share of the run; on a long log the pass and its writer thread already keep
the cores busy, and the statistics computed beside them only add their memory to the pass's
(a 400 s stereo log: a peak of 184 MB against 150 MB, in the same time): there they are
computed first.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from functools import partial
from typing import TypeVar

from processors.calibration.joint import BoardView, JointResult
from processors.calibration.uncertainty import UncertaintyMap, projection_uncertainty
from processors.calibration.validation import CrossValidation, cross_validate
from replay.messages import F64

T = TypeVar("T")

#: "far away": the uncertainty and cross-validation of rays
FAR_M = 1e4
#: the statistics run beside the caller only for views of at most this many corners in all
#: (a 40 s stereo log of 8 poses repeated holds 6 700, 400 s 67 000)
BACKGROUND_CORNERS = 10_000

__all__ = ["BACKGROUND_CORNERS", "FAR_M", "CameraStatistics", "camera_statistics"]


@dataclass(frozen=True)
class CameraStatistics:
    """What a camera's solution says of its own accuracy: the uncertainty of its
    projections (at the working range and far away) and the halves' cross-validation."""

    uncertainty: UncertaintyMap
    rays_uncertainty: UncertaintyMap
    cross_validation: CrossValidation | None


def _every_camera(joint: JointResult, views: list[BoardView], points: F64,
                  sizes: list[tuple[int, int]], disc_diameter_m: float | None,
                  ) -> list[CameraStatistics]:
    validation = cross_validate(points, views, sizes, joint.options, range_m=FAR_M,
                                disc_diameter_m=disc_diameter_m)
    return [CameraStatistics(projection_uncertainty(joint.problem, index),
                             projection_uncertainty(joint.problem, index, range_m=FAR_M),
                             validation[index] if validation is not None else None)
            for index in range(len(sizes))]


def _in_background(work: Callable[[], T]) -> Future[T]:
    """``work``'s result, computed on a thread of its own. Not a daemon: a process that
    ends early (an error, Ctrl-C) waits for it, as native code stopped mid-way at the
    interpreter's exit would abort the process."""
    future: Future[T] = Future()

    def run() -> None:
        try:
            future.set_result(work())
        except BaseException as err:  # handed to whoever reads the result
            future.set_exception(err)
    threading.Thread(target=run, name="camlog-statistics").start()
    return future


def _one_camera(every: Future[list[CameraStatistics]], index: int) -> Future[CameraStatistics]:
    """Camera ``index``'s share of ``every``, when it is done (its error if it failed)."""
    mine: Future[CameraStatistics] = Future()

    def hand_over(done: Future[list[CameraStatistics]]) -> None:
        error = done.exception()
        if error is not None:
            mine.set_exception(error)
        else:
            mine.set_result(done.result()[index])
    every.add_done_callback(hand_over)
    return mine


def camera_statistics(joint: JointResult, views: list[BoardView], points: F64,
                      sizes: list[tuple[int, int]], *, disc_diameter_m: float | None,
                      background: bool) -> list[Future[CameraStatistics]]:
    """Each camera's statistics from the joint solve of ``views`` (``points``: the board's
    ``(N, 3)``; ``sizes``: the images'), computed here or, with ``background`` and views of
    at most :data:`BACKGROUND_CORNERS` corners, on a thread of their own: reading a result
    then waits for them, and raises their error."""
    work = partial(_every_camera, joint, views, points, sizes, disc_diameter_m)
    every: Future[list[CameraStatistics]]
    if background and sum(len(v.point_ids) for v in views) <= BACKGROUND_CORNERS:
        every = _in_background(work)
    else:
        every = Future()
        every.set_result(work())
    return [_one_camera(every, index) for index in range(len(sizes))]
