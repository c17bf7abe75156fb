"""Lagrange interpolation over a camera's frame times, and the stencils that may take part."""

from __future__ import annotations

import numpy as np
import pytest

from processors.time_offset.interpolation import Stencils, lagrange_weights


def test_a_cubic_through_four_uneven_samples_is_exact_with_its_derivative() -> None:
    times = np.array([[0.0, 0.9, 2.1, 3.0], [-1.0, 0.1, 1.0, 2.2]])
    t = np.array([1.4, 0.55])
    weights, derivative = lagrange_weights(times, t)
    cubic = times ** 3 - 2 * times ** 2 + 0.5
    np.testing.assert_allclose(np.sum(weights * cubic, axis=1), t ** 3 - 2 * t ** 2 + 0.5)
    np.testing.assert_allclose(np.sum(derivative * cubic, axis=1), 3 * t ** 2 - 4 * t)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0)


def test_at_a_sample_the_weights_pick_it() -> None:
    weights, _ = lagrange_weights(np.array([[0.0, 1.0, 2.0, 3.0]]), np.array([2.0]))
    np.testing.assert_allclose(weights, [[0.0, 0.0, 1.0, 0.0]], atol=1e-15)


def test_shapes_are_checked() -> None:
    with pytest.raises(ValueError, match=r"\(N, K\)"):
        lagrange_weights(np.zeros(4), np.zeros(1))


def test_a_query_takes_the_stencil_around_it() -> None:
    stencils = Stencils(np.arange(10, dtype=np.float64) * 0.1, 4)
    start, found = stencils.locate(np.array([0.35, 0.05, 0.85, 0.91, -0.1]))
    assert start[0] == 2 and found[0]  # samples 2..5 around 0.35
    assert not found[1]  # before the second sample: no sample before the bracket's left
    assert not found[2]  # after the second-to-last sample
    assert not found[3] and not found[4]


def test_a_stencil_never_spans_a_dropped_frame_or_an_unusable_sample() -> None:
    times = np.array([0.0, 0.1, 0.2, 0.3, 0.5, 0.6, 0.7, 0.8])  # 0.4 dropped
    stencils = Stencils(times, 4)
    _, found = stencils.locate(np.array([0.15, 0.25, 0.45, 0.65]))
    assert found.tolist() == [True, False, False, True]
    usable = np.ones(8, bool)
    usable[6] = False
    _, found = Stencils(times, 4, usable).locate(np.array([0.15, 0.65]))
    assert found.tolist() == [True, False]


def test_sample_times_must_increase() -> None:
    with pytest.raises(ValueError, match="increasing"):
        Stencils(np.array([0.0, 0.1, 0.1]), 2)
