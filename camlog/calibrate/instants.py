"""From frames to the solver's views: instants, stereo pairs and held poses.

The frames become instants — one per camera frame, or one per set of frames the cameras shot
at the same time (an approximately paired frame joins its partners only while the board holds
still: 7 ms apart a moving board is at another pose). Consecutive instants that show the board
held still become one view per camera, their corners averaged (:mod:`processors.calibration.
holds`: the frames of a hold share the detector's error, so they are one observation, made
more precise). Every view of every camera then goes into one least-squares problem
(:func:`processors.calibration.joint.calibrate_cameras`); nothing is selected away.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from processors.calibration.board import Board
from processors.calibration.holds import Seen, frame_scatter_px, holds
from processors.calibration.joint import BoardView
from processors.resync import pair_stamps

from ..errors import CalibrationError
from .views import SNAPSHOT_GAP_S, CameraViews, DetectedFrame, size_hint

#: an approximately paired stereo frame joins its partner while the board moves less than
#: this (px per frame) in both
STILL_PX = 0.25

__all__ = ["STILL_PX", "Instant", "ViewsOfRig", "rig_views", "stereo_pairs"]


@dataclass(frozen=True)
class Instant:
    """Frames shot at one instant: camera -> frame index."""

    frames: dict[int, int]
    stamp_ns: int


@dataclass(frozen=True)
class ViewsOfRig:
    """The solver's input and how it maps back: ``views[i]`` is camera ``views[i].camera``
    over the frames ``frames_of[i]`` (a hold: their corners averaged)."""

    views: list[BoardView]
    frames_of: list[list[int]]  # per view, its frames (of its camera)
    pairs: list[tuple[int, int]]  # two cameras: (left view, right view) of each instant
    candidates: list[list[int]]  # per camera, frames whose board passed every check
    frame_scatter_px: float | None  # frame-to-frame scatter of held corners


def _stamp_pairs(left: CameraViews, right: CameraViews,
                 approximate_s: float | None) -> list[tuple[int, int]]:
    """(left frame, right frame) indices shot at the same time (or within the slop); maybe
    none."""
    left_ns = np.array([f.stamp_ns for f in left.frames], dtype=np.int64)
    right_ns = np.array([f.stamp_ns for f in right.frames], dtype=np.int64)
    if approximate_s is None:
        _common, li, ri = np.intersect1d(left_ns, right_ns, return_indices=True)
        return list(zip(li.tolist(), ri.tolist(), strict=True))
    pairing = pair_stamps(np.sort(left_ns), np.sort(right_ns),
                          slop_ns=round(approximate_s * 1e9))
    order_l, order_r = np.argsort(left_ns), np.argsort(right_ns)
    return [(int(order_l[a]), int(order_r[b]))
            for a, b in zip(pairing.left_index, pairing.right_index, strict=True)]


def stereo_pairs(left: CameraViews, right: CameraViews,
                 approximate_s: float | None) -> list[tuple[int, int]]:
    """(left frame, right frame) indices shot at the same time (or within the slop); an
    error when there are none."""
    pairs = _stamp_pairs(left, right, approximate_s)
    if not pairs:
        left_ns = np.array([f.stamp_ns for f in left.frames], dtype=np.int64)
        right_ns = np.array([f.stamp_ns for f in right.frames], dtype=np.int64)
        gap = np.min(np.abs(left_ns[:, None] - right_ns[None, :])) / 1e6 \
            if len(left_ns) * len(right_ns) <= 4_000_000 else float("nan")
        how = "within the slop" if approximate_s is not None else "with identical stamps"
        raise CalibrationError(
            f"{left.source.image_topic} and {right.source.image_topic} never pair {how} "
            f"(closest stamps {gap:.3f} ms apart); use --approximate SEC or resync the log"
        )
    return pairs


def _candidates(views: CameraViews, board: Board, note: str) -> list[int]:
    """Distinct frames whose board passed every check; an error naming why when none did."""
    found = [f for f in views.distinct() if f.detection is not None]
    topic = views.source.image_topic
    if not found:
        raise CalibrationError(
            f"no {board.cols}x{board.rows} "
            f"{'board' if board.pattern == 'chessboard' else board.pattern} found in "
            f"{len(views.frames)} frames of "
            f"{topic}{size_hint(views, board)}{note}")
    candidates = [f.index for f in views.frames if f.candidate]
    if not candidates:
        reasons = sorted({f.reason or f.detection.reason for f in found if f.detection})
        raise CalibrationError(f"{topic}: every {board.cols}x{board.rows} board found was "
                               "rejected "
                               f"({'; '.join(reasons)}){size_hint(views, board)}")
    return candidates


@dataclass(frozen=True)
class _Stillness:
    """One camera's frames in time order, grouped into runs over which its board stood still
    (consecutive frames repeating each other or whose corners moved at most
    :data:`STILL_PX`): per frame, the stamps its run starts and ends at, and whether it is a
    snapshot (no other frame within :data:`~.views.SNAPSHOT_GAP_S`: motion not observable)."""

    start_ns: dict[int, int]
    end_ns: dict[int, int]
    snapshot: set[int]

    @classmethod
    def of(cls, views: CameraViews) -> _Stillness:
        frames = sorted(views.frames, key=lambda f: f.stamp_ns)
        runs: list[list[DetectedFrame]] = []
        for before, frame in zip([None, *frames], frames, strict=False):
            if before is not None and _same_board(before, frame):
                runs[-1].append(frame)
            else:
                runs.append([frame])
        start = {f.index: run[0].stamp_ns for run in runs for f in run}
        end = {f.index: run[-1].stamp_ns for run in runs for f in run}
        stamps = np.array([f.stamp_ns for f in frames], dtype=np.int64)
        gaps = np.diff(stamps) / 1e9
        alone = np.minimum(np.concatenate([[np.inf], gaps]),
                           np.concatenate([gaps, [np.inf]])) >= SNAPSHOT_GAP_S
        return cls(start, end, {frames[int(i)].index for i in np.flatnonzero(alone)})


def _same_board(before: DetectedFrame, after: DetectedFrame) -> bool:
    """Whether consecutive frames of one camera show the board at one pose."""
    if after.duplicate:
        return True
    a, b = before.detection, after.detection
    return a is not None and b is not None and a.accepted and b.accepted \
        and np.array_equal(a.ids, b.ids) \
        and float(np.linalg.norm(a.corners_px - b.corners_px, axis=1).mean()) <= STILL_PX


def _one_pose(stillness: list[_Stillness], cameras: list[CameraViews],
              at: tuple[tuple[int, int], tuple[int, int]]) -> bool:
    """Whether two approximately paired frames ((camera, frame), (camera, frame)) show one
    pose: one camera saw its board stand still from its frame to the other's stamp (a board
    that moved between the two stamps, e.g. to its next held pose, is at another pose in
    each), or both are snapshots."""
    (a, a_frame), (b, b_frame) = at
    a_ns, b_ns = cameras[a].frames[a_frame].stamp_ns, cameras[b].frames[b_frame].stamp_ns
    if a_ns > b_ns:
        (a, a_frame, a_ns), (b, b_frame, b_ns) = (b, b_frame, b_ns), (a, a_frame, a_ns)
    return (stillness[a].end_ns[a_frame] >= b_ns or stillness[b].start_ns[b_frame] <= a_ns
            or (a_frame in stillness[a].snapshot and b_frame in stillness[b].snapshot))


def _sources(views: CameraViews) -> list[int]:
    """Per frame, the distinct frame it shows (itself, or the one it repeats byte for byte)."""
    out: list[int] = []
    for frame in views.frames:
        out.append(out[-1] if frame.duplicate and out else frame.index)
    return out


def _instants(cameras: list[CameraViews], candidates: list[list[int]],
              approximate_s: float | None) -> list[Instant]:
    """Every candidate frame in one instant, frames of cameras shot at the same time sharing
    one, in time order. Cameras pair two by two (0 with 1, 0 with 2, ..., 1 with 2, ...); a
    pair joins its frames' instants unless that would put two frames of one camera in one."""
    usable = [set(c) for c in candidates]
    source = [_sources(c) for c in cameras]
    stillness = [_Stillness.of(c) for c in cameras] if approximate_s is not None else []

    joined: dict[tuple[int, int], dict[int, int]] = {}  # (camera, frame) -> its instant
    for a, b in combinations(range(len(cameras)), 2):
        pairs = stereo_pairs(cameras[a], cameras[b], approximate_s) if len(cameras) == 2 \
            else _stamp_pairs(cameras[a], cameras[b], approximate_s)
        for a_frame, b_frame in pairs:
            # a repeated frame stands for the frame it repeats
            ai, bi = source[a][a_frame], source[b][b_frame]
            if ai not in usable[a] or bi not in usable[b]:
                continue
            mine, theirs = joined.get((a, ai), {a: ai}), joined.get((b, bi), {b: bi})
            if mine.keys() & theirs.keys():
                continue
            if approximate_s is not None and not _one_pose(stillness, cameras,
                                                           ((a, a_frame), (b, b_frame))):
                continue
            merged = dict(sorted({**mine, **theirs}.items()))
            for key in merged.items():
                joined[key] = merged
    out = [Instant(frames, cameras[first].frames[frames[first]].stamp_ns)
           for frames in {id(f): f for f in joined.values()}.values()
           for first in (min(frames),)]
    for camera, views in enumerate(cameras):
        out += [Instant({camera: i}, views.frames[i].stamp_ns)
                for i in candidates[camera] if (camera, i) not in joined]
    return sorted(out, key=lambda instant: (instant.stamp_ns, sorted(instant.frames.items())))


def _unlinked(cameras: int, instants: list[Instant]) -> list[int]:
    """Cameras that share no instant with camera 0, directly or through other cameras."""
    reached, grown = {0}, True
    while grown:
        grown = False
        for instant in instants:
            if len(instant.frames) > 1 and reached & instant.frames.keys() \
                    and not instant.frames.keys() <= reached:
                reached |= instant.frames.keys()
                grown = True
    return [c for c in range(cameras) if c not in reached]


def _check_linked(cameras: list[CameraViews], instants: list[Instant],
                  approximate_s: float | None) -> None:
    """An error when a camera never sees the board at an instant another camera sees it
    (directly, or through a chain of cameras, with the first one)."""
    alone = _unlinked(len(cameras), instants) if len(cameras) > 1 else []
    if not alone:
        return
    still = "" if approximate_s is None else (
        f" with the board still in {'both' if len(cameras) == 2 else 'each'} (a moving board "
        "is at another pose in each camera; hold it still, or resync the log)")
    if len(cameras) == 2:
        raise CalibrationError(
            f"{cameras[0].source.image_topic} and {cameras[1].source.image_topic} never see "
            f"the board at the same instant{still}")
    others = ", ".join(c.source.namespace for i, c in enumerate(cameras) if i not in alone)
    raise CalibrationError(
        f"{cameras[alone[0]].source.image_topic} never sees the board at the same instant as "
        f"{others}, directly or through another camera{still}; the rig's cameras must share "
        "views to be calibrated together")


def rig_views(cameras: list[CameraViews], board: Board, *, approximate_s: float | None,
              stereo_note: bool) -> ViewsOfRig:
    """The solver's views of every camera: instants, held poses averaged."""
    candidates = [_candidates(v, board, f" (camera {v.source.namespace})" if stereo_note
                              else "") for v in cameras]
    instants = _instants(cameras, candidates, approximate_s)
    _check_linked(cameras, instants, approximate_s)
    seen = [{c: Seen(cameras[c].detection(i).ids, cameras[c].corners(i))
             for c, i in instant.frames.items()} for instant in instants]
    groups = holds(seen)
    views: list[BoardView] = []
    frames_of: list[list[int]] = []
    pairs: list[tuple[int, int]] = []
    for number, group in enumerate(groups):
        at: dict[int, int] = {}
        for camera, mean in sorted(group.mean.items()):
            frames = [instants[m].frames[camera] for m in group.members]
            speeds = [cameras[camera].frames[f].speed_px for f in frames]
            speed = 0.0 if len(frames) > 1 or speeds[0] is None else float(speeds[0])
            at[camera] = len(views)
            views.append(BoardView(camera, number, mean.point_ids, mean.corners_px,
                                   speed_px=speed))
            frames_of.append(frames)
        if len(cameras) == 2 and len(at) == 2:
            pairs.append((at[0], at[1]))
    return ViewsOfRig(views, frames_of, pairs, candidates, frame_scatter_px(seen, groups))
