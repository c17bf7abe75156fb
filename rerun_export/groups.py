"""Which of several logs share one rerun recording: a log and the logs made from it.

Two logs are related when their time ranges overlap and they feed the same camera: a topic
namespace both have (a log and the outputs ``camlog process --drop-input`` wrote for it, a
resynced log and its processed pairs), or an output one of them places by ``frame_id`` on a
camera of the other. Related logs are merged in log time into one recording; every other
log gets a recording of its own, so logs made at different times (or of different rigs at
the same simulated time) keep their own timelines.
"""

from __future__ import annotations

from collections.abc import Sequence

from replay.formats import LogReader

from .survey import Survey
from .topics import Kind, classify

__all__ = ["related_groups"]

#: kinds whose frame_id names the camera that records them
_CAMERA_KINDS = frozenset({Kind.IMAGE, Kind.CAMERA_INFO, Kind.CALIBRATED_INFO})
#: kinds whose namespace is a camera's (text, skipped and other series name none)
_OF_A_CAMERA = _CAMERA_KINDS | {Kind.RECTIFIED, Kind.DETECTIONS, Kind.RESIDUALS,
                                Kind.VIEW_ERROR, Kind.PROCESSED_IMAGE, Kind.MASK,
                                Kind.POINT_2D, Kind.SCALAR, Kind.EDGES, Kind.GROUND_TRUTH,
                                Kind.UNCERTAINTY}


def related_groups(readers: Sequence[LogReader], chosen: Sequence[Sequence[str]],
                   found: Survey) -> list[list[int]]:
    """Indices of ``readers`` in groups of related logs (see the module), in input order.
    ``chosen[i]``: the topics of log ``i`` taken into account; ``found``: their survey."""
    namespaces: list[set[str]] = []
    camera_frames: list[set[str]] = []
    placed_frames: list[set[str]] = []
    for reader, topics in zip(readers, chosen, strict=True):
        routes = {t: classify(t, reader.topics[t].msgtype, found.outputs) for t in topics}
        namespaces.append({r.namespace for r in routes.values()
                           if r.namespace and r.kind in _OF_A_CAMERA})
        frames = {t: found.frame_ids[t] for t in topics if found.frame_ids.get(t)}
        camera_frames.append({f for t, f in frames.items() if routes[t].kind in _CAMERA_KINDS})
        placed_frames.append({f for t, f in frames.items() if routes[t].by_frame})
    parent = list(range(len(readers)))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i in range(len(readers)):
        for j in range(i + 1, len(readers)):
            shared = (namespaces[i] & namespaces[j] or placed_frames[i] & camera_frames[j]
                      or placed_frames[j] & camera_frames[i] or placed_frames[i] & placed_frames[j])
            if shared and _overlap(readers[i], readers[j]):
                parent[root(j)] = root(i)
    groups: dict[int, list[int]] = {}
    for i in range(len(readers)):
        groups.setdefault(root(i), []).append(i)
    return sorted(groups.values())


def _overlap(a: LogReader, b: LogReader) -> bool:
    """Whether the logs' time ranges share an instant (unknown ranges count as shared)."""
    if None in (a.start_ns, a.end_ns, b.start_ns, b.end_ns):
        return True
    assert a.start_ns is not None and a.end_ns is not None
    assert b.start_ns is not None and b.end_ns is not None
    return a.start_ns <= b.end_ns and b.start_ns <= a.end_ns
