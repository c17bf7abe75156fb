"""The default viewer layout, so that a first look needs no arranging.

Top row: one 2D view per camera, side by side (a grid beyond three), each showing the
camera's images with every overlay that belongs to them; cameras that share a frame_id (a
camera's raw and re-stamped streams) are tabs of one cell, so a stereo rig reads as a left
and a right image. A camera shown through pinhole views (:mod:`rerun_export.lens`) has its
raw image and each view side by side; a view also shows the 3D entities of its camera
(calibrated board poses, ground truth) as rerun projects them (the calibration's uncertainty
map shows over the view in 3D only). Middle row (when present):
the rectified images side by side, with horizontal guide rows, and other processed images.
Bottom row: one time-series view per kind of metric, then tabs with the 3D rig (when the log
knows it, or a camera has pinhole views; a lone camera's seen from just behind it) and the
text records. The side panels and the time
panel start collapsed (the time bar stays), leaving the window to the views; the time panel
starts on the ``log_time`` timeline.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import rerun.blueprint as rrb

from .scene import CameraPlan, ScenePlan

__all__ = ["LOG_TIME", "REPLAY_TIME", "STAMP_TIME", "make_blueprint"]

LOG_TIME = "log_time"
STAMP_TIME = "header_stamp"
REPLAY_TIME = "replay_time"  # camlog play: the wall clock of the replay


def _row(views: list[Any]) -> Any:
    if len(views) <= 3:
        return rrb.Horizontal(*views)
    return rrb.Grid(*views, grid_columns=math.ceil(math.sqrt(len(views))))


def make_blueprint(plan: ScenePlan, *, timeline: str = LOG_TIME, follow: bool = False,
                   recordings: Sequence[tuple[str, ScenePlan]] = ()) -> rrb.Blueprint:
    """Blueprint of a planned scene; ``follow`` keeps the time cursor on the newest data.
    ``recordings``: (name, plan) of several recordings that share the application id (so
    this one layout): a tab each, named after its log, laid out from its own plan."""
    time_panel = rrb.TimePanel(timeline=timeline, play_state="following" if follow else None,
                               state="collapsed")
    panels = (time_panel, rrb.BlueprintPanel(state="collapsed"),
              rrb.SelectionPanel(state="collapsed"))
    if recordings:
        tabs = [tab for name, part in recordings if (tab := _layout(part, name)) is not None]
        root = rrb.Tabs(*tabs) if tabs else None
    else:
        root = _layout(plan)
    if root is None:  # nothing camlog lays out: let the viewer choose
        return rrb.Blueprint(*panels, auto_views=True)
    return rrb.Blueprint(root, *panels)


def _behind_the_camera(plan: ScenePlan) -> Any:
    """The 3D view's eye of a one-camera scene shown through views: behind and above the
    camera, looking along its axis at its view's image and the 3D entities in front of it
    (None otherwise: rerun frames the scene)."""
    if len(plan.cameras) != 1:
        return None
    (cam,) = plan.cameras.values()
    if not cam.views:
        return None
    pose = cam.world_from_camera if cam.world_from_camera is not None else np.eye(4)
    centre, rotation = pose[:3, 3], pose[:3, :3]
    depth = plan.image_plane_distance_m
    forward, up = rotation[:, 2], -rotation[:, 1]  # optical z, image up (-y)
    return rrb.EyeControls3D(position=centre - 0.6 * depth * forward + 0.3 * depth * up,
                             look_target=centre + depth * forward, eye_up=up)


def _camera_views(cam: CameraPlan) -> Any:
    """A camera's 2D view; its raw image and each pinhole view side by side when it has
    them."""
    if not cam.views:
        return rrb.Spatial2DView(origin=cam.entity, name=cam.namespace)
    views = [rrb.Spatial2DView(origin=cam.raw_entity, name=f"{cam.namespace} (raw)")]
    for view in cam.views:
        # 3D entities of the camera, projected through the view's pinhole
        views.append(rrb.Spatial2DView(
            origin=f"{cam.entity}/{view.name}", name=f"{cam.namespace} ({view.name})",
            contents=["$origin/**", f"{cam.entity}/calibration/board/**",
                      f"{cam.entity}/ground_truth/**", "- $origin/uncertainty/**"]))
    return rrb.Horizontal(*views, name=cam.namespace)  # the name of its tab, if it is one


def _layout(plan: ScenePlan, name: str | None = None) -> Any:
    """The views of one plan in rows (None when there is nothing to lay out)."""
    by_frame: dict[str, list[Any]] = {}
    for cam in plan.cameras.values():
        if cam.viewable:  # cameras without a frame_id each get a cell of their own
            cell = by_frame.setdefault(cam.frame_id or cam.namespace, [])
            cell.append(_camera_views(cam))
    cameras = [cell[0] if len(cell) == 1 else rrb.Tabs(*cell) for cell in by_frame.values()]
    rectified = [rrb.Spatial2DView(origin=entity, name=entity.removeprefix("rectified"))
                 for entity in plan.rectified]
    rectified += [rrb.Spatial2DView(origin=entity, name=entity.removeprefix("processed"))
                  for entity in plan.images]
    bottom: list[Any] = [rrb.TimeSeriesView(origin=s.origin, name=s.title) for s in plan.series]
    tabs: list[Any] = []
    if plan.rig.world_from_camera or any(cam.views for cam in plan.cameras.values()):
        tabs.append(rrb.Spatial3DView(origin="world", name="rig (3D)",
                                      eye_controls=_behind_the_camera(plan)))
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
    if not rows:
        return None
    return rrb.Vertical(*rows, row_shares=shares, name=name)
