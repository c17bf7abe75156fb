"""Progress bars: a bar that is off does nothing and loads nothing."""

from __future__ import annotations

from tqdm import tqdm

from replay.progress import progress_bar


def test_a_bar_that_is_off_counts_nothing_and_is_no_tqdm() -> None:
    with progress_bar(total=3, unit="msg", desc="convert", progress=False) as bar:
        bar.update()
        bar.update(2)
    assert not isinstance(bar, tqdm)


def test_a_bar_that_is_on_is_tqdm_counting_to_its_total() -> None:
    with progress_bar(total=3, unit="msg", desc="convert", progress=True) as bar:
        bar.update(3)
        assert isinstance(bar, tqdm)
        assert (bar.n, bar.total, bar.unit) == (3, 3, "msg")
