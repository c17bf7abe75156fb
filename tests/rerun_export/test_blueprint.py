"""The default layout: a cell per physical camera, a tab per recording, panels collapsed."""

from __future__ import annotations

from typing import Any

import numpy as np

from replay.pinhole_views import PinholeView
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


def test_a_camera_shown_through_views_has_them_beside_its_raw_image() -> None:
    lens = plan(("/fish", "fish_optical"))
    k = np.array([[100.0, 0, 31.5], [0, 100.0, 23.5], [0, 0, 1]])
    lens.cameras["/fish"].views = [PinholeView(name, k, 64, 48, np.eye(3), 0.8)
                                   for name in ("undistorted", "wide")]
    blueprint = make_blueprint(lens)
    (cell,) = cells(blueprint.root_container)
    assert [v.origin for v in cell.contents] == ["raw/fish", "world/fish/undistorted",
                                                 "world/fish/wide"]
    # the camera's 3D entities are projected into each view; the uncertainty map is not
    undistorted = cell.contents[1]
    assert undistorted.contents == ["$origin/**", "world/fish/calibration/board/**",
                                    "world/fish/ground_truth/**", "- $origin/uncertainty/**"]
    # and the camera gets a 3D view (no rig pose: at the origin), seen from just behind and
    # above it (image up is -y), looking along its optical axis (+z)
    (bottom,) = blueprint.root_container.contents[1:]
    (view_3d,) = bottom.contents[0].contents
    eye = view_3d.properties["EyeControls3D"]
    ((x, y, z),) = eye.position.as_arrow_array().to_pylist()
    ((tx, ty, tz),) = eye.look_target.as_arrow_array().to_pylist()
    assert x == 0 and y < 0 and z < 0 and (tx, ty) == (0, 0) and tz > 0
    assert eye.eye_up.as_arrow_array().to_pylist() == [[0, -1, 0]]
