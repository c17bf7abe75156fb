"""Per-camera frame bookkeeping: decimation, stamps seen, stale overlays."""

from __future__ import annotations

from rerun_export.frames import RECENT, CameraFrames


def test_every_third_image_and_its_overlays() -> None:
    frames = CameraFrames(every=3)
    kept = [frames.take(stamp) for stamp in range(100, 110)]
    assert kept == [True, False, False] * 3 + [True]
    assert [frames.shows(s) for s in (100, 101, 103, 104)] == [True, False, True, False]
    assert frames.shows(999)  # an overlay of a frame never seen is drawn
    assert frames.saw(105) and not frames.saw(999)


def test_memory_is_bounded() -> None:
    frames = CameraFrames(every=2)
    for stamp in range(10 * RECENT):
        frames.take(stamp)
    assert len(frames.recent) == len(frames.dropped) == RECENT
    assert frames.saw(10 * RECENT - 1) and not frames.saw(0)


def test_stale_overlays_are_returned_once() -> None:
    frames = CameraFrames()
    frames.drawn("corners", 10)
    frames.drawn("status", 10)
    frames.drawn("mask", 20)
    assert frames.stale(10) == []  # overlays of the current frame stay
    assert sorted(frames.stale(20)) == ["corners", "status"]
    assert frames.stale(20) == [] and frames.stale(30) == ["mask"]


def test_a_repeated_image_keeps_its_overlays() -> None:
    frames = CameraFrames()
    assert frames.stale(10, b"board at pose A") == []
    frames.drawn("corners", 10)
    assert frames.stale(20, b"board at pose A") == []  # the same view: corners stay
    assert frames.stale(30, b"board at pose A") == []
    assert frames.stale(40, b"board at pose B") == ["corners"]
    frames.drawn("corners", 40)
    assert frames.stale(50) == ["corners"]  # without a key every new frame clears
