"""An offset between two cameras' stamps as measured from their images, and what both
methods share: the robust least-squares fit of the offset and its honest uncertainty.

The offset ``offset_s`` is how much later the second camera stamps an instant than the
first: a frame of the second camera stamped ``s`` was exposed when the first camera would
have stamped ``s - offset_s``. Re-stamping the second camera by ``-offset_s`` makes both
cameras' stamps say the same of the same instant.

Residuals of one frame share errors (a board pose, a frame's blur), and neighbouring frames
share the samples they are interpolated from, so the standard deviation is the
cluster-robust ("sandwich") one over windows of :data:`CLUSTER_FRAMES` frames rather than
the one that counts every residual as independent.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np
import numpy.typing as npt

from replay.messages import F64

from ..errors import ProcessorError

__all__ = ["CLUSTER_FRAMES", "NotObservableError", "OffsetEstimate", "robust_fit"]

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]

#: frames per cluster of the sandwich covariance: neighbouring frames share errors
CLUSTER_FRAMES = 10
#: a residual beyond this many robust sigmas is an outlier
OUTLIER_SIGMAS = 5.0
#: consistent with a normal distribution: sigma = MAD_TO_SIGMA * median absolute deviation
MAD_TO_SIGMA = 1.4826


class NotObservableError(ProcessorError):
    """The images do not show the offset (nothing moves, no shared view)."""


@dataclass(frozen=True)
class OffsetEstimate:
    """How much later the second camera stamps an instant than the first (``offset_s``)
    with its standard deviation, the frames that carried it (where the scene moved) of the
    frames fitted, the RMS residual (px) and how it was measured (``board`` or
    ``features``); the board method also gives the rig it solved, ``second_from_first``
    ``(4, 4)``."""

    offset_s: float
    std_s: float
    frames: int
    frames_fitted: int
    rms_px: float
    method: str
    second_from_first: F64 | None = None

    @property
    def offset_ms(self) -> float:
        """The offset in milliseconds."""
        return 1000.0 * self.offset_s

    @property
    def std_ms(self) -> float:
        """Its standard deviation in milliseconds."""
        return 1000.0 * self.std_s

    def describe(self) -> str:
        """One line: the offset with its sigma and the frames that carried it."""
        return (f"{self.offset_ms:+.3f} ± {self.std_ms:.3f} ms (1 sigma), from the "
                f"{self.method} in {self.frames} moving frames of {self.frames_fitted}")


S = TypeVar("S")


@dataclass(frozen=True)
class Fit(Generic[S]):
    """A robust least-squares solution: the state, the sandwich covariance ``(U, U)`` of
    its increments there, the residuals ``(R,)``, their inlier mask and robust sigma."""

    state: S
    covariance: F64
    residuals: F64
    inliers: B8
    sigma: float


def robust_fit(linearize: Callable[[S], tuple[F64, F64]], advance: Callable[[S, F64], S],
               state: S, *, clusters: I64, tolerance: F64, iterations: int = 15) -> Fit[S]:
    """Gauss-Newton from ``state``: ``linearize(state)`` gives the residuals ``(R,)`` and
    their Jacobian ``(R, U)`` in the increments that ``advance(state, step)`` applies,
    until every step is within ``tolerance`` ``(U,)``; residuals beyond
    :data:`OUTLIER_SIGMAS` robust sigmas are left out between rounds. The covariance is
    clustered by ``clusters`` ``(R,)`` (the residuals of one cluster share errors)."""
    r, jacobian = linearize(state)
    inliers = np.isfinite(r) & np.all(np.isfinite(jacobian), axis=1)
    sigma = math.nan
    for _round in range(4):
        for _ in range(iterations):
            use = inliers & np.isfinite(r) & np.all(np.isfinite(jacobian), axis=1)
            j = jacobian[use]
            step = np.linalg.lstsq(j.T @ j, -(j.T @ r[use]), rcond=None)[0]
            state = advance(state, step)
            r, jacobian = linearize(state)
            if np.all(np.abs(step) <= tolerance):
                break
        finite = np.isfinite(r) & np.all(np.isfinite(jacobian), axis=1)
        sigma = MAD_TO_SIGMA * float(np.median(np.abs(r[finite & inliers]))) \
            if np.any(finite & inliers) else math.nan
        kept = finite & (np.abs(r) <= OUTLIER_SIGMAS * sigma)
        if np.array_equal(kept, inliers):
            break
        inliers = kept
    use = inliers & np.isfinite(r) & np.all(np.isfinite(jacobian), axis=1)
    return Fit(state, _sandwich(jacobian[use], r[use], clusters[use]), r, use, sigma)


def _sandwich(jacobian: F64, residuals: F64, clusters: I64) -> F64:
    """``(J^T J)^-1 (sum_c g_c g_c^T) (J^T J)^-1`` with ``g_c = J_c^T r_c`` per cluster,
    times ``C / (C - 1)`` for ``C`` clusters."""
    bread = np.linalg.pinv(jacobian.T @ jacobian)
    ids, index = np.unique(clusters, return_inverse=True)
    scores = np.zeros((len(ids), jacobian.shape[1]))
    np.add.at(scores, index, jacobian * residuals[:, None])
    meat = scores.T @ scores * (len(ids) / max(len(ids) - 1, 1))
    return np.asarray(bread @ meat @ bread, dtype=np.float64)
