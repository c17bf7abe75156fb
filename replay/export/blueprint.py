"""The default viewer layout, so that a first look needs no arranging.

Top row: one 2D view per camera, side by side (a grid beyond three), each showing the
camera's images with every overlay that belongs to them. Middle row (when present): the
rectified images side by side, with horizontal guide rows, and other processed images.
Bottom row: one time-series view per kind of metric, then tabs with the 3D rig (when the
log knows it) and the text records. The time panel starts on the ``log_time`` timeline.
"""

from __future__ import annotations

import math
from typing import Any

import rerun.blueprint as rrb

from .scene import ScenePlan

__all__ = ["LOG_TIME", "REPLAY_TIME", "STAMP_TIME", "make_blueprint"]

LOG_TIME = "log_time"
STAMP_TIME = "header_stamp"
REPLAY_TIME = "replay_time"  # camlog play: the wall clock of the replay


def _row(views: list[Any]) -> Any:
    if len(views) <= 3:
        return rrb.Horizontal(*views)
    return rrb.Grid(*views, grid_columns=math.ceil(math.sqrt(len(views))))


def make_blueprint(plan: ScenePlan, *, timeline: str = LOG_TIME,
                   follow: bool = False) -> rrb.Blueprint:
    """Blueprint of a planned scene; ``follow`` keeps the time cursor on the newest data."""
    time_panel = rrb.TimePanel(timeline=timeline, play_state="following" if follow else None)
    cameras = [rrb.Spatial2DView(origin=cam.entity, name=cam.namespace)
               for cam in plan.cameras.values() if cam.viewable]
    rectified = [rrb.Spatial2DView(origin=entity, name=entity.removeprefix("rectified"))
                 for entity in plan.rectified]
    rectified += [rrb.Spatial2DView(origin=entity, name=entity.removeprefix("processed"))
                  for entity in plan.images]
    bottom: list[Any] = [rrb.TimeSeriesView(origin=s.origin, name=s.title) for s in plan.series]
    tabs: list[Any] = []
    if plan.rig.world_from_camera:
        tabs.append(rrb.Spatial3DView(origin="world", name="rig (3D)"))
    tabs += [rrb.TextDocumentView(origin=entity, name=entity.removeprefix("text"))
             for entity in plan.texts]
    if tabs:
        bottom.append(rrb.Tabs(*tabs))
    rows: list[Any] = []
    shares: list[float] = []
    for views, share in ((cameras, 3.0), (rectified, 2.0), (bottom, 2.0)):
        if views:
            rows.append(_row(views))
            shares.append(share)
    if not rows:  # nothing camlog lays out: let the viewer choose
        return rrb.Blueprint(time_panel, auto_views=True)
    return rrb.Blueprint(rrb.Vertical(*rows, row_shares=shares), time_panel)
