"""Approximate-time pairing of two independently stamped cameras (stereo resync).

The policy is message_filters' ApproximateTime for two streams, solved exactly offline:

1. a left and a right frame may pair only when ``|right_ns - left_ns| <= slop_ns``;
2. every frame is used at most once;
3. the number of pairs is maximal, so every frame whose partner exists within the slop is
   paired unless pairing it would leave another frame without its partner;
4. among those, the total stamp spread ``sum |right_ns - left_ns|`` is minimal;
5. remaining ties go to the earlier frame (deterministic).

Because spread on a line is a Monge cost, uncrossing two crossed pairs never increases the
spread or leaves the slop, so the optimum is monotone (pairs increase on both sides) and a
banded dynamic programme over the two sorted stamp arrays finds it in
``O(N * frames within slop)`` time.

A pair is re-stamped with the *later* of its two stamps (:func:`pair_stamp_ns`): the pair
is complete then, so a live node could publish it at that instant, and the new stamps
increase strictly with the pairs.

Example::

    >>> p = pair_stamps(np.array([0, 33, 66]), np.array([11, 77]), slop_ns=16)
    >>> p.left_index.tolist(), p.right_index.tolist(), p.left_unpaired.tolist()
    ([0, 2], [0, 1], [1])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from replay.records import OffsetStats, ResyncStats

from .errors import ConfigError, StampsError

I64 = npt.NDArray[np.int64]

#: slop when neither side has two stamps to estimate a frame period from
FALLBACK_SLOP_NS = 20_000_000

_UP, _LEFT, _DIAG = 0, 1, 2


@dataclass(frozen=True, slots=True)
class Pairing:
    """Result of :func:`pair_stamps`; all arrays are indices into the input stamp arrays.

    ``left_index`` and ``right_index`` (P,) are the pairs, both strictly increasing;
    ``left_unpaired`` (U,) and ``right_unpaired`` (V,) the frames left without a partner.
    """

    left_index: I64
    right_index: I64
    left_unpaired: I64
    right_unpaired: I64
    slop_ns: int

    def __len__(self) -> int:
        return len(self.left_index)


def _check_stamps(side: str, stamps_ns: npt.ArrayLike) -> I64:
    stamps = np.asarray(stamps_ns)
    if stamps.ndim != 1 or (stamps.size and not np.issubdtype(stamps.dtype, np.integer)):
        raise StampsError(f"{side} stamps must be a 1-D integer array, got {stamps.dtype}"
                         f"{list(stamps.shape)}")
    stamps = stamps.astype(np.int64)
    if np.any(np.diff(stamps) < 0):
        raise StampsError(f"{side} stamps must be sorted")
    return stamps


def frame_period_ns(stamps_ns: npt.ArrayLike) -> int | None:
    """Median spacing of sorted stamps (robust to drops); None with fewer than two."""
    stamps = np.asarray(stamps_ns, dtype=np.int64)
    return int(np.median(np.diff(stamps))) if stamps.size >= 2 else None


def default_slop_ns(left_ns: npt.ArrayLike, right_ns: npt.ArrayLike) -> int:
    """Half the larger median frame period of the two sides.

    With evenly clocked cameras no frame is then within the slop of two consecutive partner
    frames, so the pairing is unambiguous; :data:`FALLBACK_SLOP_NS` without stamps to
    estimate from.
    """
    periods = [p for p in (frame_period_ns(left_ns), frame_period_ns(right_ns)) if p]
    return max(periods) // 2 if periods else FALLBACK_SLOP_NS


def pair_stamps(left_ns: npt.ArrayLike, right_ns: npt.ArrayLike, *, slop_ns: int) -> Pairing:
    """Optimal approximate-time pairs of two sorted stamp arrays (N,) and (M,), see module doc."""
    left = _check_stamps("left", left_ns)
    right = _check_stamps("right", right_ns)
    if slop_ns < 0:
        raise ConfigError(f"slop must be >= 0, got {slop_ns} ns")
    # Row i (a left frame) can pair with the right frames [lo[i], hi[i]); both bounds grow
    # with i. V(i, j) is the best (pairs, -spread) using left[:i] and right[:j]; only
    # j in [lo[i-1], hi[i-1]] is stored per row since V(i, j) = V(i, hi[i-1]) beyond it
    # and V(i, j) = V(i-1, j) below it.
    lo = np.searchsorted(right, left - slop_ns, side="left").tolist()
    hi = np.searchsorted(right, left + slop_ns, side="right").tolist()
    left_list, right_list = left.tolist(), right.tolist()
    moves: list[bytearray] = []
    prev: list[tuple[int, int]] = [(0, 0)]
    prev_lo = prev_hi = 0
    for i, stamp in enumerate(left_list):
        lo_i, hi_i = lo[i], hi[i]
        # V(i, j) for j >= lo_i is prev[min(j, prev_hi) - prev_lo]
        row = [prev[min(lo_i, prev_hi) - prev_lo]]
        row_moves = bytearray()
        for j in range(lo_i, hi_i):
            best, move = prev[min(j + 1, prev_hi) - prev_lo], _UP
            if row[-1] > best:
                best, move = row[-1], _LEFT
            pairs, neg_spread = prev[min(j, prev_hi) - prev_lo]
            diag = (pairs + 1, neg_spread - abs(right_list[j] - stamp))
            if diag > best:
                best, move = diag, _DIAG
            row.append(best)
            row_moves.append(move)
        moves.append(row_moves)
        prev, prev_lo, prev_hi = row, lo_i, hi_i

    pairs_found: list[tuple[int, int]] = []
    i, j = len(left_list), len(right_list)
    while i > 0 and j > 0:
        lo_p, hi_p = lo[i - 1], hi[i - 1]
        if j > hi_p:
            j = hi_p
        elif j <= lo_p:
            i -= 1
        else:
            move = moves[i - 1][j - lo_p - 1]
            if move == _DIAG:
                pairs_found.append((i - 1, j - 1))
                i, j = i - 1, j - 1
            elif move == _UP:
                i -= 1
            else:
                j -= 1
    pairs_found.reverse()
    index = np.array(pairs_found, dtype=np.int64).reshape(-1, 2)
    return Pairing(
        left_index=index[:, 0],
        right_index=index[:, 1],
        left_unpaired=np.setdiff1d(np.arange(len(left)), index[:, 0]).astype(np.int64),
        right_unpaired=np.setdiff1d(np.arange(len(right)), index[:, 1]).astype(np.int64),
        slop_ns=int(slop_ns),
    )


def pair_stamp_ns(left_ns: npt.ArrayLike, right_ns: npt.ArrayLike) -> I64:
    """Common stamp of pairs: the later of the two stamps, elementwise."""
    return np.maximum(np.asarray(left_ns, dtype=np.int64), np.asarray(right_ns, dtype=np.int64))


def pairing_stats(left_ns: npt.ArrayLike, right_ns: npt.ArrayLike,
                  pairing: Pairing) -> ResyncStats:
    """Counts, unpaired stamps, and ``right - left`` offsets in ns of a pairing."""
    left = np.asarray(left_ns, dtype=np.int64)
    right = np.asarray(right_ns, dtype=np.int64)
    offset_ns = right[pairing.right_index] - left[pairing.left_index]
    summary = OffsetStats(int(offset_ns.min()), int(np.median(offset_ns)),
                          int(offset_ns.max())) if offset_ns.size else None
    return ResyncStats(
        pairs=len(pairing),
        slop_ns=pairing.slop_ns,
        stamp_policy="later of the two stamps",
        left_frames=int(left.size),
        right_frames=int(right.size),
        left_unpaired_stamps_ns=left[pairing.left_unpaired].tolist(),
        right_unpaired_stamps_ns=right[pairing.right_unpaired].tolist(),
        offset_right_minus_left_ns=summary,
    )
