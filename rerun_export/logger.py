"""Log a stream of raw messages into a rerun recording, following a :class:`ScenePlan`.

Every message is logged on two timelines: ``log_time`` (when it was stored) and
``header_stamp`` (its header, absent for messages without one). Images are decimated per
camera (``every``); an overlay is dropped with the frame it belongs to (same stamp). A
camera's next image clears the overlays of older frames, unless it repeats the last image
byte for byte or a calibration view covers the frames up to a later stamp (a held pose keeps
its corners on all its frames); topics with a message for every image of their camera
(ground truth, processed every frame) need no clearing: the next message replaces them.
Camera_info is decoded only when its bytes (minus the stamp) change. With a JPEG quality,
images are encoded on worker threads (OpenCV releases the GIL) while the next messages are
read, and reach rerun in message order. Frames that do not decode (a cut JPEG, video
before its first keyframe) are counted per topic and reported.

A camera whose lens is not a pinhole (:mod:`rerun_export.lens`) gets its pinhole views from
each camera_info that changes its model (maps built once per model); each of its raw
images is remapped to every view on the worker threads, and its overlays go with the raw
image (:attr:`~rerun_export.scene.CameraPlan.raw_entity`), drawn through the real lens. The
camera's 3D entities (the calibration's board poses, the simulator's targets) go under
its entity, where rerun projects them onto the views. A camera's calibrated camera_info,
when the log has one, draws it: the calibration's board poses were solved with it."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import rerun as rr

from replay.bounded import reindent_json
from replay.errors import EncodingError, ReplayError
from replay.formats.base import RawMessage
from replay.messages import CompressedImage, Image, Message, PointStamped, Text
from replay.records import ViewResiduals

from .cameras import (
    CENTROID_RADIUS,
    CORNER_RADIUS,
    CYAN,
    GREEN,
    GUIDE_RADIUS,
    ORANGE,
    ORDER_DETECTIONS,
    ORDER_EDGES,
    ORDER_MASK,
    RED,
    CameraDrawing,
)
from .emitter import Flush
from .images import still_frame
from .options import LoggerOptions
from .overlays import CLASSES, edge_classes, mask_classes
from .scene import ScenePlan, image_entity, series_entity, text_entity
from .topics import Kind, Route
from .uncertainty import uncertainty_overlays

__all__ = ["LoggerOptions", "SceneLogger"]


class SceneLogger(CameraDrawing):
    """Logs raw messages of the planned topics to ``rec``; counts what it logged (a
    camera's own messages are drawn by :class:`~rerun_export.cameras.CameraDrawing`).
    ``columns``: send images, points and clears in columns of several frames (an export;
    a live replay sends each frame as it comes)."""

    def __init__(self, rec: rr.RecordingStream, plan: ScenePlan, options: LoggerOptions,
                 *, decode: Callable[[RawMessage], Message], flush: Flush = None,
                 columns: bool = False) -> None:
        super().__init__(rec, plan, options, decode=decode, flush=flush, columns=columns)
        self._guides: set[str] = set()
        self._handlers: dict[Kind, Callable[[RawMessage, Route], None]] = {
            Kind.IMAGE: self._image, Kind.CAMERA_INFO: self._camera_info,
            Kind.CALIBRATED_INFO: self._camera_info, Kind.RECTIFIED: self._rectified,
            Kind.PROCESSED_IMAGE: self._rectified, Kind.DETECTIONS: self._detections,
            Kind.RESIDUALS: self._residuals,
            Kind.VIEW_ERROR: self._series, Kind.SCALAR: self._series,
            Kind.STEREO_OFFSET: self._series, Kind.POINT_SERIES: self._series,
            Kind.MASK: self._segmentation, Kind.EDGES: self._segmentation,
            Kind.POINT_2D: self._point_2d, Kind.GROUND_TRUTH: self._ground_truth,
            Kind.TEXT: self._text, Kind.UNCERTAINTY: self._uncertainty,
        }

    # --- setup -----------------------------------------------------------------------------

    def log_static(self) -> None:
        """World axes, segmentation classes, rig poses and series styles (timeless)."""
        rec = self.rec
        rec.log("/", rr.AnnotationContext([(i, label, color) for i, (label, color)
                                           in CLASSES.items()]), static=True)
        up = rr.ViewCoordinates.RIGHT_HAND_Z_UP if self.plan.rig.world_is_scenario \
            else rr.ViewCoordinates.RDF
        rec.log("world", up, static=True)
        for cam in self.plan.cameras.values():
            if cam.world_from_camera is not None:
                pose = cam.world_from_camera
                rec.log(cam.entity, rr.Transform3D(translation=pose[:3, 3], mat3x3=pose[:3, :3]),
                        static=True)
        for route_topic, route in self.plan.routes.items():
            if route.kind is Kind.POINT_SERIES:
                rec.log(series_entity(route, route_topic),
                        rr.SeriesLines(names=["x", "y", "z"]), static=True)

    # --- entry point -----------------------------------------------------------------------

    def log(self, raw: RawMessage, *, replay_ns: int | None = None) -> None:
        """Log one raw message of a planned topic (others are ignored); ``replay_ns`` also
        places it on the ``replay_time`` timeline (``camlog play``)."""
        self._replay_ns = replay_ns
        route = self.plan.routes.get(raw.topic)
        if route is None or raw.topic in self.plan.skipped:
            return
        handler = self._handlers.get(route.kind)
        if handler is None:
            return
        try:
            handler(raw, route)
        except (ReplayError, ValueError) as err:
            what = "frames did not decode (not shown; " if isinstance(err, EncodingError) \
                else "messages not shown ("
            count, first = self._failed.get(raw.topic, (0, f"{what}first at log time "
                                                           f"{raw.log_time_ns}: {err})"))
            self._failed[raw.topic] = (count + 1, first)

    # --- what a camera's processors and calibration add ------------------------------------

    def _rectified(self, raw: RawMessage, route: Route) -> None:
        """A rectified (with guide rows) or other processed image, in its own view."""
        message = self._still_image(raw)
        cam = self._camera_of(route, message)
        if cam is not None and not cam.frames.shows(message.stamp_ns):
            return
        self._times(raw, message.stamp_ns)
        entity = image_entity(route.kind, raw.topic)
        if route.kind is Kind.RECTIFIED and entity not in self._guides:
            self._guides.add(entity)
            self._guide_rows(entity, message)
        self._emit(entity + "/image", self._archetype(message))

    def _guide_rows(self, entity: str, message: Image | CompressedImage) -> None:
        """Horizontal lines every 1/12 of the height: matching rows of a rectified pair."""
        image = still_frame(message)
        rows = [[[0.0, v], [float(image.width), v]] for v in np.linspace(0, image.height, 13)[1:-1]]
        self.rec.log(entity + "/rows", rr.LineStrips2D(rows, colors=[CYAN], radii=GUIDE_RADIUS),
                     static=True)

    def _detections(self, raw: RawMessage, route: Route) -> None:
        message = self._still_image(raw)
        cam = self.cameras[route.namespace]
        stamp = message.stamp_ns
        if not cam.frames.shows(stamp):
            return
        self._times(raw, stamp)
        self._overlay(raw, cam, f"{cam.plan.raw_entity}/calibration/detections", stamp,
                      self._archetype(message, draw_order=ORDER_DETECTIONS))
        why = self.plan.rejected.get(cam.plan.namespace, {}).get(stamp)
        if why is not None:
            image = still_frame(message)
            self._overlay(raw, cam, f"{cam.plan.raw_entity}/calibration/status", stamp, rr.Boxes2D(
                mins=[[0, 0]], sizes=[[image.width, image.height]], colors=[RED],
                labels=[f"rejected: {why}"]))

    def _residuals(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, Text)
        view = ViewResiduals.from_message(message)
        cam = self.cameras[route.namespace]
        if not cam.frames.shows(view.stamp_ns):
            return
        self._times(raw, view.stamp_ns)
        base, scale = f"{cam.plan.raw_entity}/calibration", self.options.residual_scale
        self._overlay(raw, cam, f"{base}/corners", view.stamp_ns,
                      self._points(f"{base}/corners", view.corners_px, GREEN, CORNER_RADIUS))
        self._overlay(raw, cam, f"{base}/residuals", view.stamp_ns, rr.Arrows2D(
            origins=view.corners_px, vectors=view.residuals_px * scale, colors=[ORANGE]))
        if cam.size is not None:
            width, height = cam.size
            self._overlay(raw, cam, f"{base}/status", view.stamp_ns, rr.Boxes2D(
                mins=[[0, 0]], sizes=[[width, height]], colors=[GREEN],
                labels=[f"used: view RMS {view.rms_px:.3f} px (residuals ×{scale:g})"]))
        if cam.shown_through_views and view.corners_in_camera_m is not None:
            board = f"{cam.plan.entity}/calibration/board"
            self._overlay(raw, cam, board, view.stamp_ns, self._points(
                board, view.corners_in_camera_m, GREEN, CORNER_RADIUS, dimension=3))
            self._board_plane(cam, view.corners_in_camera_m)
        if view.until_ns is not None:  # a held pose: the overlays stay on all its frames
            cam.frames.hold(view.stamp_ns, view.until_ns)

    def _series(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, PointStamped)
        if route.kind is Kind.SCALAR and route.by_frame:
            cam = self._camera_of(route, message)
            namespace = cam.plan.namespace if cam is not None else message.frame_id
        else:
            namespace = route.namespace
        entity = series_entity(route, namespace)
        self._times(raw, message.stamp_ns)
        match route.kind:
            case Kind.STEREO_OFFSET:
                values: Any = float(message.point[0]) * 1e3
            case Kind.POINT_SERIES:
                values = message.point
            case _:
                values = float(message.point[0])
        self._emit(entity, rr.Scalars(values))

    def _segmentation(self, raw: RawMessage, route: Route) -> None:
        message = self._still_image(raw)
        cam = self._camera_of(route, message)
        if cam is None or not cam.frames.shows(message.stamp_ns):
            return
        image = still_frame(message)
        if route.kind is Kind.MASK:
            classes, opacity, order = mask_classes(image.rgb8()), 0.5, ORDER_MASK
        else:
            classes, opacity, order = edge_classes(image.mono8()), 0.8, ORDER_EDGES
        self._times(raw, message.stamp_ns)
        self._overlay(raw, cam, f"{cam.plan.raw_entity}/{route.entity}", message.stamp_ns,
                      rr.SegmentationImage(classes, opacity=opacity, draw_order=order))

    def _point_2d(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, PointStamped)
        cam = self._camera_of(route, message)
        if cam is None or not cam.frames.shows(message.stamp_ns):
            return
        self._times(raw, message.stamp_ns)
        entity = f"{cam.plan.raw_entity}/{route.entity}"
        self._overlay(raw, cam, entity, message.stamp_ns, self._points(
            entity, [message.point[:2]], CYAN, CENTROID_RADIUS, label=route.label or None))

    def _uncertainty(self, raw: RawMessage, route: Route) -> None:
        """The calibration's projection uncertainty map, over the camera's views (or its
        image under its pinhole), for the whole recording, with contours at round values."""
        cam = self.cameras[route.namespace]
        message = self._still_image(raw)
        if cam.size is None:
            return
        sigma_px = still_frame(message).pixels.astype(np.float64)
        for entity, archetype in uncertainty_overlays(sigma_px, cam.size, cam.lens,
                                                      camera_entity=cam.plan.entity):
            self.rec.log(entity, archetype, static=True)

    def _text(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, Text)
        indented = reindent_json(message.data)  # None: shown as it is
        text = message.data if indented is None else f"```json\n{indented}\n```"
        self._times(raw, None)
        self._emit(text_entity(raw.topic), rr.TextDocument(text, media_type="text/markdown"))
