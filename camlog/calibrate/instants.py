"""From frames to the solver's views: instants, stereo pairs and held poses.

The frames become instants — one per camera frame, or one per set of frames the cameras shot
at the same time (an approximately paired frame joins its partners only while the board holds
still: 7 ms apart a moving board is at another pose). Consecutive instants that show the board
held still become one view per camera, their corners averaged (:mod:`processors.calibration.
holds`: the frames of a hold share the detector's error, so they are one observation, made
more precise). Every view of every camera then goes into one least-squares problem
(:func:`processors.calibration.joint.calibrate_cameras`); nothing is selected away.

A camera whose stamps are ``offset`` late relative to the first camera's (measured from the
board's motion, :mod:`.offsets`) joins the first camera's frames by time instead: each frame
of the first camera is paired with the frame of the other camera exposed nearest to it, and
when the board moves in between, that camera's corners are interpolated to the first
camera's exposure (a cubic through 4 of its consecutive frames that show the same corners,
:mod:`processors.time_offset.interpolation`), so that the pair shows the board at one pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from processors.calibration.board import Board
from processors.calibration.holds import Seen, frame_scatter_px, holds
from processors.calibration.joint import BoardView
from processors.resync import pair_stamps
from processors.time_offset.interpolation import Stencils

from ..errors import CalibrationError
from .views import SNAPSHOT_GAP_S, CameraViews, DetectedFrame, size_hint

#: an approximately paired stereo frame joins its partner while the board moves less than
#: this (px per frame) in both
STILL_PX = 0.25
#: a frame of a camera with an offset joins a first camera's frame as it is when the board
#: moves less than this (px) between their exposures; else its corners are interpolated
SAME_INSTANT_PX = 0.01
#: frames of the cubic that interpolates a camera's corners to another camera's exposure
STENCIL = 4

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


def _timed_pairs(first: CameraViews, other: CameraViews, offset_ns: int,
                 usable: tuple[set[int], set[int]]) -> list[tuple[int, int, Seen | None]]:
    """(frame of ``first``, frame of ``other`` exposed nearest to it, the other camera's
    corners at the first frame's exposure or None: the other frame's own), for ``other``
    stamping ``offset_ns`` later than ``first``; each frame in one pair at most. A frame is
    paired as it is when the board moves less than :data:`SAME_INSTANT_PX` between the two
    exposures, with its corners interpolated when :data:`STENCIL` consecutive frames around
    the exposure show the same corners, and not at all otherwise."""
    mine = sorted(usable[1], key=lambda i: other.frames[i].stamp_ns)
    if len(mine) < 2:
        return []
    stamps = np.array([other.frames[i].stamp_ns for i in mine], dtype=np.int64)
    period_ns = float(np.median(np.diff(stamps)))
    origin = int(stamps[0])
    times_s = np.asarray((stamps - origin) * 1e-9, dtype=np.float64)
    if np.any(np.diff(times_s) <= 0):
        return []
    stencils = Stencils(times_s, STENCIL)
    best: dict[int, tuple[int, int, Seen | None]] = {}  # other frame -> its pair
    for frame in sorted(usable[0]):
        target_ns = first.frames[frame].stamp_ns + offset_ns
        nearest = int(np.argmin(np.abs(stamps - target_ns)))
        gap_ns = abs(int(stamps[nearest]) - target_ns)
        if gap_ns > period_ns / 2:
            continue
        if nearest in best and abs(other.frames[mine[nearest]].stamp_ns
                                   - (first.frames[best[nearest][0]].stamp_ns + offset_ns)) \
                <= gap_ns:
            continue
        speed = other.frames[mine[nearest]].speed_px
        if speed is not None and speed * gap_ns / period_ns <= SAME_INSTANT_PX:
            best[nearest] = (frame, mine[nearest], None)
            continue
        seen = _interpolated(other, mine, stencils, (target_ns - origin) * 1e-9)
        if seen is not None:
            best[nearest] = (frame, mine[nearest], seen)
    return sorted(best.values())


def _interpolated(other: CameraViews, frames: list[int], stencils: Stencils, t_s: float
                  ) -> Seen | None:
    """A camera's corners at ``t_s`` (s after its first usable frame) from the cubic through
    the :data:`STENCIL` usable ``frames`` around it; None when they are not consecutive or
    do not show the same corners."""
    start, found = stencils.locate(np.array([t_s]))
    if not found[0]:
        return None
    chosen = [other.frames[frames[int(start[0]) + k]] for k in range(STENCIL)]
    detections = [f.detection for f in chosen]
    if any(d is None for d in detections):
        return None
    ids = [d.ids for d in detections if d is not None]
    if not all(np.array_equal(ids[0], i) for i in ids[1:]):
        return None
    weights, _ = stencils.weights(np.array([t_s]), start)
    corners = np.einsum("k,kmd->md", weights[0],
                        np.stack([d.corners_px for d in detections if d is not None]))
    return Seen(ids[0], corners)


def _instants(cameras: list[CameraViews], candidates: list[list[int]],
              approximate_s: float | None, offsets_ns: list[int | None] | None = None
              ) -> tuple[list[Instant], dict[tuple[int, int], Seen]]:
    """Every candidate frame in one instant, frames of cameras shot at the same time sharing
    one, in time order, and the corners of the frames interpolated to their instant
    ((camera, frame) -> what it saw then). Cameras pair two by two (0 with 1, 0 with 2, ...,
    1 with 2, ...); a pair joins its frames' instants unless that would put two frames of
    one camera in one. A camera with an offset (``offsets_ns[c]``, late relative to camera
    0) pairs with camera 0 by time (:func:`_timed_pairs`), with no other camera by stamp."""
    usable = [set(c) for c in candidates]
    source = [_sources(c) for c in cameras]
    stillness = [_Stillness.of(c) for c in cameras] if approximate_s is not None else []
    timed = offsets_ns or [None] * len(cameras)
    interpolated: dict[tuple[int, int], Seen] = {}

    joined: dict[tuple[int, int], dict[int, int]] = {}  # (camera, frame) -> its instant
    for a, b in combinations(range(len(cameras)), 2):
        offset_ns = timed[b]
        if offset_ns is not None or timed[a] is not None:
            if a or offset_ns is None:
                continue  # a camera with an offset pairs with camera 0 alone
            pairs = []
            for a_frame, b_frame, seen in _timed_pairs(cameras[a], cameras[b], offset_ns,
                                                       (usable[a], usable[b])):
                pairs.append((a_frame, b_frame))
                if seen is not None:
                    interpolated[(b, b_frame)] = seen
        else:
            pairs = stereo_pairs(cameras[a], cameras[b], approximate_s) \
                if len(cameras) == 2 else _stamp_pairs(cameras[a], cameras[b], approximate_s)
        for a_frame, b_frame in pairs:
            # a repeated frame stands for the frame it repeats
            ai, bi = source[a][a_frame], source[b][b_frame]
            if ai not in usable[a] or bi not in usable[b]:
                continue
            mine, theirs = joined.get((a, ai), {a: ai}), joined.get((b, bi), {b: bi})
            if mine.keys() & theirs.keys():
                continue
            if approximate_s is not None and offset_ns is None \
                    and not _one_pose(stillness, cameras, ((a, a_frame), (b, b_frame))):
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
    return (sorted(out, key=lambda instant: (instant.stamp_ns, sorted(instant.frames.items()))),
            {key: seen for key, seen in interpolated.items() if key in joined})


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
              stereo_note: bool, offsets_ns: list[int | None] | None = None) -> ViewsOfRig:
    """The solver's views of every camera: instants, held poses averaged; a camera with an
    offset (``offsets_ns[c]``: how much later it stamps an instant than camera 0) joins
    camera 0's frames by time (see the module's text)."""
    candidates = [_candidates(v, board, f" (camera {v.source.namespace})" if stereo_note
                              else "") for v in cameras]
    instants, interpolated = _instants(cameras, candidates, approximate_s, offsets_ns)
    _check_linked(cameras, instants, approximate_s)
    seen = [{c: interpolated.get((c, i)) or Seen(cameras[c].detection(i).ids,
                                                  cameras[c].corners(i))
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
