"""Frame selection: every N-th frame and a rate limit by header stamp."""

from __future__ import annotations

import numpy as np
import pytest

from processors.errors import OptionValueError
from processors.throttle import EveryNth, KeepAll, RateLimit, make_throttle, throttle_mask

MS = 1_000_000


def test_every_third_frame_is_the_chapters_10hz_over_30hz() -> None:
    kept = throttle_mask(np.arange(10) * 33 * MS, EveryNth(3))
    assert np.flatnonzero(kept).tolist() == [0, 3, 6, 9]
    assert throttle_mask(np.arange(4), EveryNth(1)).all()


def test_rate_limit_keeps_at_most_hz_by_stamp() -> None:
    rng = np.random.default_rng(1)
    stamps = np.round(np.arange(300) * 1e9 / 30 + rng.normal(0, 2 * MS, 300)).astype(np.int64)
    kept = stamps[throttle_mask(stamps, RateLimit(10.0))]
    assert np.all(np.diff(kept) >= 100 * MS)
    # with 2 ms jitter a kept frame is sometimes 4 frames after the previous, never 5
    assert np.all(np.diff(kept) < 140 * MS)
    assert 70 <= kept.size <= 100


def test_rate_limit_on_exact_stamps() -> None:
    stamps = np.arange(0, 1000 * MS, 100 * MS // 3)  # 30 Hz
    kept = throttle_mask(stamps, RateLimit(10.0))
    assert stamps[kept].tolist() == [0, 133_333_332, 266_666_664, 399_999_996, 533_333_328,
                                     666_666_660, 799_999_992, 933_333_324]
    assert throttle_mask([0, 50 * MS, 100 * MS], RateLimit(10.0)).tolist() == [True, False, True]


def test_make_throttle_chooses_one() -> None:
    assert isinstance(make_throttle(), KeepAll)
    assert isinstance(make_throttle(every=2), EveryNth)
    assert isinstance(make_throttle(rate=5), RateLimit)
    for make, options in ((lambda: make_throttle(every=2, rate=5), ("every", "rate")),
                          (lambda: EveryNth(0), ("every",)), (lambda: RateLimit(0), ("rate",))):
        with pytest.raises(OptionValueError) as err:
            make()
        # options by name, never by a command line's flag (the command words those)
        assert err.value.options == options and "--" not in str(err.value)
