"""The entity layout of a recording, planned from a survey before any message is logged.

Entity paths (``{ns}`` is a camera namespace such as ``stereo_camera/left``)::

    world                                  ViewCoordinates (Z up with a scenario, else RDF)
    world/{ns}                             Transform3D (rig pose, when known), Pinhole (a
                                           pinhole camera's) and CameraInfo (the camera model
                                           in full: rerun_export.camera_records)
    world/{ns}/image                       Image, or EncodedImage (JPEG/PNG)
    world/{ns}/calibration/detections      the calibration's annotated image
    world/{ns}/calibration/corners         Points2D, corners of a used view
    world/{ns}/calibration/residuals       Arrows2D, residuals x --residual-scale
    world/{ns}/calibration/status          Boxes2D framing the image: used / rejected
    world/{ns}/{entity}                    a processor's mask or edges (SegmentationImage) or
                                           2-D point (Points2D), e.g. red_pixels/mask,
                                           red_pixels/centroid, edges
    world/{ns}/ground_truth/{target}       Points2D, the target's points projected
    rectified/{topic}                      rectified images, and rows: LineStrips2D guides
    processed/{topic}                      other images processors computed
    metrics/{series}/{ns}                  Scalars (view RMS px, red count, offset ms, ...)
    text/{topic}                           TextDocument (scenario, summaries, stats)

A camera whose lens is not a pinhole (distortion, a fisheye, a rectified stereo camera)
cannot be shown by rerun's Pinhole as it is. Its raw image and every overlay drawn through
its real lens move to a 2D space of their own, and the camera gets pinhole views
(:mod:`rerun_export.lens`) made from its raw images::

    raw/{ns}/image, raw/{ns}/...           the raw image and the overlays listed above
    world/{ns}                             Transform3D (rig pose) and CameraInfo
    world/{ns}/{view}                      Pinhole of the view (undistorted, wide or
                                           rectified), Transform3D (R for rectified) and
                                           PinholeView (its K in float64, field, coverage)
    world/{ns}/{view}/image                the raw image remapped to the view
    world/{ns}/{view}/uncertainty          the calibration's projection uncertainty map
    world/{ns}/calibration/board           Points3D, a used view's corners where the
                                           calibration solved them (camera frame)
    world/{ns}/ground_truth/{target}       Points3D, the target's points (camera frame)

rerun projects the 3D entities onto every view (in the 3D view and in a view's 2D view).

Processor outputs recorded in the log go under the camera of their source image, at the
entity their processor declared. Outputs known only by name (the chapter's
``/image_converter/...``) go under the camera whose images carry their ``frame_id``; a frame
no camera has becomes a camera ``world/frame/{frame_id}``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from replay.messages import F64, CameraInfo
from replay.msgtypes import FOXGLOVE_COMPRESSED_VIDEO as VIDEO
from replay.pinhole_views import PinholeView, pinhole_views
from replay.records import CalibrationSummary, Scenario
from replay.wire import record_msgtype

from .options import UNDISTORTED_SCALE
from .rig import Rig, rig_poses
from .survey import Survey
from .topics import Kind, Route

__all__ = ["CameraPlan", "ScenePlan", "SeriesPlan", "camera_entity", "plan_scene",
           "raw_entity"]

#: kinds whose messages are drawn inside a camera's 2D view
_VIEWABLE = frozenset({Kind.IMAGE, Kind.DETECTIONS, Kind.RESIDUALS, Kind.MASK,
                       Kind.POINT_2D, Kind.EDGES, Kind.GROUND_TRUTH, Kind.UNCERTAINTY})
#: kind -> (metrics group, view title); a processor's scalar names its own
SERIES: dict[Kind, tuple[str, str]] = {
    Kind.VIEW_ERROR: ("calibration_view_rms_px", "calibration view RMS (px)"),
    Kind.SCALAR: ("scalars", "processor outputs"),
    Kind.STEREO_OFFSET: ("stereo_offset_ms", "stereo stamp offset right − left (ms)"),
    Kind.POINT_SERIES: ("points", "other PointStamped topics (x, y, z)"),
}


def camera_entity(namespace: str) -> str:
    """``/stereo_camera/left`` -> ``world/stereo_camera/left``."""
    return "world/" + namespace.strip("/")


def raw_entity(namespace: str) -> str:
    """``/stereo_camera/left`` -> ``raw/stereo_camera/left``."""
    return "raw/" + namespace.strip("/")


@dataclass
class CameraPlan:
    """One camera: its namespace, entity, frame and the topics that feed it; the pinhole
    views of its lens (none for a pinhole camera) as its first camera_info describes it."""

    namespace: str
    entity: str
    frame_id: str = ""
    image_topic: str | None = None
    info_topic: str | None = None
    calibrated_info_topic: str | None = None
    viewable: bool = False
    world_from_camera: F64 | None = None
    info: CameraInfo | None = None
    views: list[PinholeView] = field(default_factory=list)

    @property
    def raw_entity(self) -> str:
        """Where the raw image and its overlays go: the camera entity of a pinhole camera,
        ``raw/{ns}`` (a 2D space of its own) for one shown through views."""
        return raw_entity(self.namespace) if self.views else self.entity

    @property
    def info_topics(self) -> list[str]:
        """The camera_info topics that describe the camera, the one it is drawn from first
        (the calibration's, when the log has one)."""
        return [t for t in (self.calibrated_info_topic, self.info_topic) if t is not None]


@dataclass(frozen=True)
class SeriesPlan:
    """A time-series view: the ``metrics/{group}`` entity subtree and its title."""

    origin: str
    title: str


@dataclass
class ScenePlan:
    """Everything the logger and the blueprint need, decided before logging."""

    routes: dict[str, Route]
    cameras: dict[str, CameraPlan]  # namespace -> plan, in display order
    frames: dict[str, list[str]]  # frame_id -> camera namespaces with that frame
    rig: Rig
    image_plane_distance_m: float
    series: list[SeriesPlan] = field(default_factory=list)
    rectified: list[str] = field(default_factory=list)  # rectified image entities
    images: list[str] = field(default_factory=list)  # other processed image entities
    texts: list[str] = field(default_factory=list)  # text document entities
    targets: dict[str, F64] = field(default_factory=dict)  # target -> points (N, 3)
    rejected: dict[str, dict[int, str]] = field(default_factory=dict)  # ns -> stamp -> why
    skipped: dict[str, str] = field(default_factory=dict)  # topic -> why it is not shown
    counts: dict[str, int] = field(default_factory=dict)  # topic -> messages in the log
    undistorted: float | None = UNDISTORTED_SCALE  # the views' size (None: no views)


def image_entity(kind: Kind, topic: str) -> str:
    """The own view of an image topic: ``/stereo/left/image_rect/compressed`` ->
    ``rectified/stereo/left/image_rect``; other processed images under ``processed/``."""
    prefix = "rectified/" if kind is Kind.RECTIFIED else "processed/"
    return prefix + topic.removesuffix("/compressed").strip("/")


def text_entity(topic: str) -> str:
    """``/camlog/scenario`` -> ``text/camlog/scenario``."""
    return "text/" + topic.strip("/")


def series_group(route: Route) -> tuple[str, str]:
    """(metrics group, view title) of a time-series route: a processor's scalar by its
    entity and label."""
    group, title = SERIES[route.kind]
    if route.kind is Kind.SCALAR:
        return route.entity or group, route.label or route.entity or title
    return group, title


def series_entity(route: Route, namespace: str) -> str:
    """``metrics/{group}/{namespace}``."""
    return f"metrics/{series_group(route)[0]}/{namespace.strip('/')}"


def orphan_namespace(frame_id: str) -> str:
    """Namespace of a camera known only by the frame of processor outputs."""
    return "/frame/" + (frame_id.replace("/", "_").strip("_") or "unnamed")


def _targets(scenario: Scenario | None) -> dict[str, F64]:
    targets = scenario.targets if scenario is not None else []
    return {t.name: points for t in targets if (points := t.points_in_target()) is not None}


def _plane_distance_m(rig: Rig, summary: CalibrationSummary | None) -> float:
    """Frustum depth: 2.5 baselines of the closest camera pair, else 0.1 m; in a
    calibration's recording at least its working range (a view's image then moves to the
    depth of each board it shows: :meth:`~.cameras.CameraDrawing._board_plane`)."""
    positions = [pose[:3, 3] for pose in rig.world_from_camera.values()]
    gaps = [float(((a - b) ** 2).sum() ** 0.5) for i, a in enumerate(positions)
            for b in positions[i + 1:]]
    gaps = [g for g in gaps if g > 1e-6]
    depth = min(max(2.5 * min(gaps), 0.02), 1.0) if gaps else 0.1
    ranges = [c.uncertainty.range_m for c in summary.cameras
              if c.uncertainty is not None] if summary is not None else []
    return max([depth, *ranges])


def _views(info: CameraInfo, scale: float) -> list[PinholeView]:
    """The pinhole views of a camera (none for a lens camlog does not know: it is drawn
    as rerun can, its raw image under a pinhole of its K)."""
    try:
        return pinhole_views(info, scale=scale)
    except (KeyError, ValueError):
        return []


def plan_scene(found: Survey, *,
               undistorted_scale: float | None = UNDISTORTED_SCALE) -> ScenePlan:
    """Lay out cameras, overlays, series and documents for the surveyed topics; cameras
    whose lens is not a pinhole get pinhole views ``undistorted_scale`` times their raw
    images' size (None: none, their raw images go under a pinhole of their K)."""
    routes = dict(found.routes)
    cameras: dict[str, CameraPlan] = {}
    skipped: dict[str, str] = {}

    def camera(ns: str) -> CameraPlan:
        if ns not in cameras:
            cameras[ns] = CameraPlan(ns, camera_entity(ns))
        return cameras[ns]

    for topic, route in sorted(routes.items()):
        kind, ns = route.kind, route.namespace
        if kind is Kind.SKIPPED:
            skipped[topic] = f"{found.topics[topic].msgtype} is not shown"
        elif kind is Kind.IMAGE:
            cam = camera(ns)
            if cam.image_topic is None or (cam.image_topic.endswith("/compressed")
                                           and not topic.endswith("/compressed")):
                if cam.image_topic is not None:
                    skipped[cam.image_topic] = f"same camera as {topic}"
                cam.image_topic = topic
                cam.frame_id = found.frame_ids.get(topic, cam.frame_id)
            else:
                skipped[topic] = f"same camera as {cam.image_topic}"
        elif kind is Kind.CAMERA_INFO:
            camera(ns).info_topic = topic
        elif kind is Kind.CALIBRATED_INFO:
            camera(ns).calibrated_info_topic = topic
        elif not route.by_frame and kind in _VIEWABLE | {Kind.RECTIFIED}:
            camera(ns)
    for cam in cameras.values():
        for info_topic in (cam.info_topic, cam.calibrated_info_topic):
            if not cam.frame_id and info_topic is not None and info_topic in found.frame_ids:
                cam.frame_id = found.frame_ids[info_topic]
    frames: dict[str, list[str]] = {}
    for ns, cam in sorted(cameras.items()):
        if cam.frame_id:
            frames.setdefault(cam.frame_id, []).append(ns)
    for topic, route in sorted(routes.items()):
        if route.by_frame and topic in found.frame_ids:
            frame = found.frame_ids[topic]
            if frame not in frames:
                ns = orphan_namespace(frame)
                camera(ns).frame_id = frame
                frames[frame] = [ns]
            if route.kind in _VIEWABLE:
                for ns in frames[frame]:
                    cameras[ns].viewable = True
        elif route.kind in _VIEWABLE and route.namespace in cameras:
            cameras[route.namespace].viewable = True
    infos: dict[str, CameraInfo] = {}
    for ns, cam in cameras.items():
        for info_topic in cam.info_topics:  # calibrated first
            if info_topic in found.camera_infos and ns not in infos:
                infos[ns] = found.camera_infos[info_topic]
        if undistorted_scale is not None and ns in infos and cam.image_topic is not None \
                and record_msgtype(found.topics[cam.image_topic].msgtype) != VIDEO:
            cam.info = infos[ns]
            cam.views = _views(infos[ns], undistorted_scale)
    ordered = dict(sorted(cameras.items()))
    rig = rig_poses(list(ordered), frame_ids={ns: c.frame_id for ns, c in ordered.items()},
                    infos=infos, scenario=found.scenario)
    for ns, pose in rig.world_from_camera.items():
        ordered[ns].world_from_camera = pose
    groups = sorted({(list(SERIES).index(r.kind), *series_group(r)) for r in routes.values()
                     if r.kind in SERIES})
    titles: dict[str, str] = {}
    for _, group, title in groups:
        titles.setdefault(group, title)  # one view per group
    series = [SeriesPlan(f"metrics/{group}", title) for group, title in titles.items()]
    return ScenePlan(
        routes=routes,
        cameras=ordered,
        frames=frames,
        rig=rig,
        image_plane_distance_m=_plane_distance_m(rig, found.calibration_summary),
        series=series,
        rectified=sorted({image_entity(r.kind, t) for t, r in routes.items()
                          if r.kind is Kind.RECTIFIED}),
        images=sorted({image_entity(r.kind, t) for t, r in routes.items()
                       if r.kind is Kind.PROCESSED_IMAGE}),
        texts=[text_entity(t) for t, r in sorted(routes.items()) if r.kind is Kind.TEXT],
        targets=_targets(found.scenario),
        rejected=found.calibration_summary.rejected_stamps()
        if found.calibration_summary is not None else {},
        skipped=skipped,
        counts={name: info.count for name, info in found.topics.items()},
        undistorted=undistorted_scale,
    )
