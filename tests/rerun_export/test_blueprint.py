"""The default layout: a cell per physical camera, a tab per recording, panels collapsed."""

from __future__ import annotations

from typing import Any

from rerun_export.blueprint import make_blueprint
from rerun_export.rig import Rig
from rerun_export.scene import CameraPlan, ScenePlan


def plan(*cameras: tuple[str, str]) -> ScenePlan:
    """A plan with viewable cameras (namespace, frame_id)."""
    plans = {ns: CameraPlan(ns, "world/" + ns.strip("/"), frame_id=frame, viewable=True)
             for ns, frame in cameras}
    return ScenePlan(routes={}, cameras=plans, frames={}, rig=Rig(),
                     image_plane_distance_m=0.1)


def cells(container: Any) -> list[Any]:
    """The cells of the camera row (the first row of a layout)."""
    return list(container.contents[0].contents)


def test_streams_of_one_camera_are_tabs_of_one_cell() -> None:
    stereo = plan(("/stereo_sync/left", "left_optical"), ("/stereo_sync/right", "right_optical"),
                  ("/unsynced/left", "left_optical"), ("/unsynced/right", "right_optical"))
    blueprint = make_blueprint(stereo)
    left, right = cells(blueprint.root_container)
    assert [v.origin for v in left.contents] == ["world/stereo_sync/left", "world/unsynced/left"]
    assert [v.origin for v in right.contents] == ["world/stereo_sync/right",
                                                  "world/unsynced/right"]
    assert blueprint.time_panel is not None and blueprint.time_panel.state == "collapsed"


def test_several_recordings_get_a_tab_each() -> None:
    stereo = plan(("/stereo_sync/left", "left_optical"))
    red = plan(("/stereo_camera/left", "left_optical"), ("/stereo_camera/right", "right_optical"))
    union = plan(("/stereo_sync/left", "left_optical"), ("/stereo_camera/left", "left_optical"),
                 ("/stereo_camera/right", "right_optical"))
    blueprint = make_blueprint(union, recordings=[("calibration.mcap", stereo),
                                                  ("red.mcap", red)])
    first, second = blueprint.root_container.contents
    assert (first.name, second.name) == ("calibration.mcap", "red.mcap")
    # unrelated cameras never share a cell, though their frame_ids match
    assert [v.origin for v in cells(first)] == ["world/stereo_sync/left"]
    assert [v.origin for v in cells(second)] == ["world/stereo_camera/left",
                                                 "world/stereo_camera/right"]
