"""Rotations: how many of a set agree with each, counted in blocks as one by one."""

from __future__ import annotations

import math

import numpy as np
import pytest

from processors.calibration import rotation


def angle_rad(a: np.ndarray, b: np.ndarray) -> float:
    return math.acos(max(-1.0, min(1.0, (float(np.trace(a.T @ b)) - 1) / 2)))


@pytest.mark.parametrize("block", [1 << 18, 7])
def test_support_counts_the_groups_holding_a_rotation_within_the_angle(
        block: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(rotation, "SUPPORT_BLOCK", block)
    rng = np.random.default_rng(3)
    common = rotation.matrices(rng.normal(size=(1, 3)))[0]
    # pairs: a rotation near a common one (or a random one) and a random one
    near = rotation.matrices(rng.normal(size=(30, 3)) * rng.uniform(0, 0.3, (30, 1))) @ common
    far = rotation.matrices(rng.normal(size=(30, 3)) * 2)
    near[::5] = far[::5][::-1]
    pairs = np.stack([near, far], axis=1).reshape(-1, 3, 3)
    limit = math.radians(10)
    counts = rotation.support(pairs, limit, group=2)
    expected = [sum(min(angle_rad(r, pairs[2 * j]), angle_rad(r, pairs[2 * j + 1])) < limit
                    for j in range(30)) for r in pairs]
    assert counts.tolist() == expected
    assert max(expected) > 5  # the common rotation's neighbours agree
    single = rotation.support(near, limit)
    assert single.tolist() == [sum(angle_rad(r, s) < limit for s in near) for r in near]
    best = int(np.argmax(single))
    assert rotation.within(near, near[best], limit).tolist() == \
        [angle_rad(near[best], s) < limit for s in near]
