"""Pure pairing of two stamp arrays: optimality, ties, drops, slop bound, empty sides."""

from __future__ import annotations

import numpy as np
import pytest

from processors.errors import ConfigError, StampsError
from processors.resync import (
    FALLBACK_SLOP_NS,
    Pairing,
    default_slop_ns,
    pair_stamp_ns,
    pair_stamps,
    pairing_stats,
)
from replay.records import OffsetStats

MS = 1_000_000


def pairs_of(p: Pairing) -> list[tuple[int, int]]:
    return list(zip(p.left_index.tolist(), p.right_index.tolist(), strict=True))


def best_value(left: list[int], right: list[int], slop: int) -> tuple[int, int]:
    """Brute force over every matching (crossing or not): (pairs, -total spread)."""
    best = (0, 0)

    def go(i: int, used: frozenset[int], pairs: int, spread: int) -> None:
        nonlocal best
        if i == len(left):
            best = max(best, (pairs, -spread))
            return
        go(i + 1, used, pairs, spread)
        for j, r in enumerate(right):
            if j not in used and abs(r - left[i]) <= slop:
                go(i + 1, used | {j}, pairs + 1, spread + abs(r - left[i]))

    go(0, frozenset(), 0, 0)
    return best


def test_matches_brute_force_on_random_streams() -> None:
    rng = np.random.default_rng(3)
    for _ in range(300):
        left = np.sort(rng.integers(0, 100, rng.integers(0, 7)))
        right = np.sort(rng.integers(0, 100, rng.integers(0, 7)))
        slop = int(rng.integers(0, 40))
        p = pair_stamps(left, right, slop_ns=slop)
        spread = np.abs(right[p.right_index] - left[p.left_index])
        assert np.all(spread <= slop)
        assert len(set(p.left_index.tolist())) == len(p) == len(set(p.right_index.tolist()))
        assert np.all(np.diff(p.left_index) > 0) and np.all(np.diff(p.right_index) > 0)
        assert (len(p), -int(spread.sum())) == best_value(left.tolist(), right.tolist(), slop)
        assert sorted([*p.left_index.tolist(), *p.left_unpaired.tolist()]) == list(
            range(len(left)))
        assert sorted([*p.right_index.tolist(), *p.right_unpaired.tolist()]) == list(
            range(len(right)))


def test_drops_leave_exactly_the_orphans_unpaired() -> None:
    period, phase = 33 * MS, 11 * MS
    frames = np.arange(20)
    left_kept = np.setdiff1d(frames, [4, 9])
    right_kept = np.setdiff1d(frames, [9, 15])
    left = left_kept * period
    right = right_kept * period + phase
    p = pair_stamps(left, right, slop_ns=default_slop_ns(left, right))
    assert left_kept[p.left_index].tolist() == right_kept[p.right_index].tolist()
    assert left_kept[p.left_unpaired].tolist() == [15]  # its right partner was dropped
    assert right_kept[p.right_unpaired].tolist() == [4]


def test_ties_go_to_the_earlier_frame() -> None:
    # one right frame exactly between two left frames, and the mirror image
    assert pairs_of(pair_stamps([0, 30], [15], slop_ns=20)) == [(0, 0)]
    assert pairs_of(pair_stamps([15], [0, 30], slop_ns=20)) == [(0, 0)]


def test_more_pairs_beat_smaller_spread() -> None:
    # pairing 10-12 (spread 2) would orphan 0 and 20; 0-12 and 10-20 pairs both
    p = pair_stamps([0, 10], [12, 20], slop_ns=12)
    assert pairs_of(p) == [(0, 0), (1, 1)]


def test_slop_is_an_inclusive_upper_bound() -> None:
    assert pairs_of(pair_stamps([0], [16], slop_ns=16)) == [(0, 0)]
    p = pair_stamps([0], [17], slop_ns=16)
    assert len(p) == 0 and p.left_unpaired.tolist() == [0] and p.right_unpaired.tolist() == [0]


@pytest.mark.parametrize(("left", "right"), [([], []), ([1, 2], []), ([], [5])])
def test_empty_sides_pair_nothing(left: list[int], right: list[int]) -> None:
    p = pair_stamps(np.array(left, dtype=np.int64), np.array(right, dtype=np.int64),
                    slop_ns=10)
    assert len(p) == 0
    assert p.left_unpaired.tolist() == list(range(len(left)))
    assert p.right_unpaired.tolist() == list(range(len(right)))
    stats = pairing_stats(left, right, p)
    assert stats.pairs == 0 and stats.offset_right_minus_left_ns is None


def test_long_streams_stay_fast_and_exact() -> None:
    rng = np.random.default_rng(0)
    n = 50_000
    left = np.arange(n) * 33 * MS + rng.integers(-MS, MS, n)
    right = np.arange(n) * 33 * MS + 11 * MS + rng.integers(-MS, MS, n)
    p = pair_stamps(left, right, slop_ns=40 * MS)  # every frame has two candidates
    assert p.left_index.tolist() == p.right_index.tolist() == list(range(n))


def test_default_slop_is_half_the_larger_period() -> None:
    assert default_slop_ns(np.arange(10) * 30, np.arange(10) * 50) == 25
    assert default_slop_ns([5], np.arange(3) * 40) == 20
    assert default_slop_ns([], [7]) == FALLBACK_SLOP_NS


def test_common_stamp_is_the_later_one_and_stats_report_offsets() -> None:
    assert pair_stamp_ns([10, 40], [12, 35]).tolist() == [12, 40]
    left, right = np.array([0, 100, 200]), np.array([5, 93, 400])
    p = pair_stamps(left, right, slop_ns=10)
    stats = pairing_stats(left, right, p)
    assert stats.pairs == 2
    assert stats.offset_right_minus_left_ns == OffsetStats(min=-7, median=-1, max=5)
    assert stats.left_unpaired_stamps_ns == [200]
    assert stats.right_unpaired_stamps_ns == [400]


def test_bad_input_is_rejected() -> None:
    with pytest.raises(StampsError, match="sorted"):
        pair_stamps([3, 1], [1], slop_ns=1)
    with pytest.raises(StampsError, match="integer"):
        pair_stamps([0.5], [1], slop_ns=1)
    with pytest.raises(ConfigError, match="slop"):
        pair_stamps([0], [1], slop_ns=-1)
