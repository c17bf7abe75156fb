"""Values sampled at a camera's frame times, interpolated to any time between them.

A smooth motion (a waved board, a moving rig) sampled at 30 Hz is a polynomial over a few
frames to well within a detector's noise: the value at ``t`` is the Lagrange polynomial
through the samples of a short stencil of consecutive frames around ``t`` (4 frames, a cubic,
for the board; 5, a quartic, for features tracked over ±2 frames). Frame times need not be
even (jitter); a stencil must not span a dropped frame (a gap of more than
:data:`MAX_GAP_PERIODS` frame periods), since that is where a polynomial through fewer
samples would guess.

Example::

    >>> w, dw = lagrange_weights(np.array([[0.0, 1.0, 2.0, 3.0]]), np.array([1.5]))
    >>> float(w @ np.array([0.0, 1.0, 8.0, 27.0])), float(dw @ np.array([0.0, 1.0, 8.0, 27.0]))
    (3.375, 6.75)
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from replay.messages import F64

__all__ = ["MAX_GAP_PERIODS", "Stencils", "lagrange_weights"]

I64 = npt.NDArray[np.int64]
B8 = npt.NDArray[np.bool_]

#: consecutive samples of a stencil lie at most this many frame periods apart
MAX_GAP_PERIODS = 1.5


def lagrange_weights(times: F64, t: F64) -> tuple[F64, F64]:
    """Weights ``(N, K)`` of the Lagrange polynomial through ``K`` samples at ``times``
    ``(N, K)`` (distinct) evaluated at ``t`` ``(N,)``, and of its derivative there: the
    value is ``weights @ samples``."""
    times = np.asarray(times, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    if times.ndim != 2 or t.shape != times.shape[:1]:
        raise ValueError(f"times must be (N, K) and t (N,), got {times.shape} and {t.shape}")
    n, k = times.shape
    weights = np.ones((n, k))
    derivative = np.zeros((n, k))
    for j in range(k):
        others = [m for m in range(k) if m != j]
        denominator = np.prod([times[:, j] - times[:, m] for m in others], axis=0)
        factors = [t - times[:, m] for m in others]
        weights[:, j] = np.prod(factors, axis=0) / denominator
        derivative[:, j] = sum(np.prod([f for i, f in enumerate(factors) if i != skip], axis=0)
                               for skip in range(len(factors))) / denominator
    return weights, derivative


class Stencils:
    """Where each query time falls among sorted sample ``times_s`` ``(N,)`` and the
    stencil of ``size`` consecutive samples that interpolates it (the bracketing pair in its
    middle), those samples' times lying at most :data:`MAX_GAP_PERIODS` frame periods
    apart and ``usable`` ``(N,)`` marking the samples that may take part (a still board's
    frame, a sample with a value)."""

    def __init__(self, times_s: F64, size: int, usable: B8 | None = None) -> None:
        self.times_s = np.asarray(times_s, dtype=np.float64)
        if self.times_s.ndim != 1 or np.any(np.diff(self.times_s) <= 0):
            raise ValueError("sample times must be 1-D and increasing")
        self.size = size
        gaps = np.diff(self.times_s)
        period = float(np.median(gaps)) if len(gaps) else 0.0
        ok = np.ones(len(self.times_s), bool) if usable is None else np.asarray(usable, bool)
        # start[k]: a stencil starting at sample k is whole (size samples, no gap, usable)
        whole = np.zeros(max(len(self.times_s) - size + 1, 0), bool)
        for k in range(len(whole)):
            whole[k] = bool(ok[k:k + size].all()
                            and np.all(gaps[k:k + size - 1] <= MAX_GAP_PERIODS * period))
        self.whole = whole
        self.period_s = period

    def locate(self, t_s: F64) -> tuple[I64, B8]:
        """For queries ``(Q,)``: the first sample of each one's stencil ``(Q,)`` and whether
        it has one (inside the samples' span, its stencil whole)."""
        t_s = np.asarray(t_s, dtype=np.float64)
        after = np.searchsorted(self.times_s, t_s, side="right")  # first sample after t
        start = after - self.size // 2
        inside = (after >= 1) & (after < len(self.times_s)) & (start >= 0) \
            & (start + self.size <= len(self.times_s))
        start = np.clip(start, 0, max(len(self.whole) - 1, 0))
        found = inside & (self.whole[start] if len(self.whole) else False)
        return start.astype(np.int64), np.asarray(found, bool)

    def weights(self, t_s: F64, start: I64) -> tuple[F64, F64]:
        """Lagrange weights ``(Q, size)`` and derivative weights at ``t_s`` ``(Q,)`` of the
        stencils starting at ``start`` ``(Q,)``."""
        index = start[:, None] + np.arange(self.size)[None, :]
        centre = self.times_s[index].mean(axis=1, keepdims=True)
        # times relative to the stencil's middle: exact arithmetic near the samples
        return lagrange_weights(self.times_s[index] - centre, np.asarray(t_s) - centre[:, 0])
