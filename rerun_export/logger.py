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
before its first keyframe) are counted per topic and reported."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import rerun as rr

from replay.bounded import reindent_json
from replay.camera import CameraModel
from replay.errors import EncodingError, ReplayError
from replay.formats.base import RawMessage
from replay.messages import (
    CameraInfo,
    CompressedImage,
    Image,
    Message,
    PointStamped,
    PoseStamped,
    Text,
)
from replay.records import ViewResiduals

from .columns import ClearRow, PointsRow
from .emitter import Emitter, Flush
from .frames import CameraFrames
from .images import image_archetype, is_keyframe, still_frame, video_sample
from .overlays import (
    CLASSES,
    edge_classes,
    header_stamp_ns,
    inside_image,
    mask_classes,
    project_target,
    stamp_free_key,
    stamp_free_view,
)
from .scene import CameraPlan, ScenePlan, image_entity, series_entity, text_entity
from .topics import Kind, Route

__all__ = ["LoggerOptions", "SceneLogger"]

Decoded = TypeVar("Decoded")


@dataclass(frozen=True)
class LoggerOptions:
    """What to draw and how: ``every`` keeps every N-th image of a camera; ``jpeg_quality``
    stores raw 8-bit images as JPEG; residual arrows are drawn ``residual_scale`` times long."""

    every: int = 1
    jpeg_quality: int | None = None
    residual_scale: float = 50.0
    ground_truth: bool = True

#: draw orders: overlays above the image, the annotated calibration image between
ORDER_DETECTIONS, ORDER_MASK, ORDER_EDGES = -9.0, -8.0, -7.0
GREEN, ORANGE, RED, YELLOW, CYAN = (60, 230, 60), (255, 150, 0), (255, 50, 50), (255, 230, 0), \
    (0, 220, 255)
CORNER_RADIUS, CENTROID_RADIUS, TRUTH_RADIUS, GUIDE_RADIUS = (
    rr.components.Radius.ui_points(r) for r in (2.5, 5.0, 1.5, 0.5))


@dataclass
class _Camera:
    """Logging state of one camera."""

    plan: CameraPlan
    info_key: bytes | None = None
    model: CameraModel | None = None  # for projecting ground truth
    size: tuple[int, int] | None = None  # (width, height) from camera_info or raw images
    frames: CameraFrames = field(default_factory=CameraFrames)


class SceneLogger:
    """Logs raw messages of the planned topics to ``rec``; counts what it logged.
    ``columns``: send images, points and clears in columns of several frames (an export;
    a live replay sends each frame as it comes)."""

    def __init__(self, rec: rr.RecordingStream, plan: ScenePlan, options: LoggerOptions,
                 *, decode: Callable[[RawMessage], Message], flush: Flush = None,
                 columns: bool = False) -> None:
        self.rec, self.plan, self.options, self._decode = rec, plan, options, decode
        # rerun's own log_time (the export's wall clock) and log_tick would clutter timelines
        rec.set_log_time_enabled(False)
        rec.set_log_tick_enabled(False)
        self.cameras = {ns: _Camera(cam, frames=CameraFrames(every=options.every))
                        for ns, cam in plan.cameras.items()}
        encoders = 2 if options.jpeg_quality is not None else 0
        self._out = Emitter(rec, encoders=encoders, flush=flush,  # flush: the sink's
                            columns=columns)
        self.counts = self._out.counts  # entity -> logged rows
        self.warnings: list[str] = []
        self._warned: set[str] = set()
        self._failed: dict[str, tuple[int, str]] = {}  # topic -> messages not shown, why
        self._guides: set[str] = set()
        self._styled: set[str] = set()  # point entities whose colour and size are logged
        self._truth: dict[str, tuple[bytes, CameraModel, Any]] = {}  # topic -> last pose
        self._replay_ns: int | None = None
        self._handlers: dict[Kind, Callable[[RawMessage, Route], None]] = {
            Kind.IMAGE: self._image, Kind.CAMERA_INFO: self._camera_info,
            Kind.CALIBRATED_INFO: self._camera_info, Kind.RECTIFIED: self._rectified,
            Kind.PROCESSED_IMAGE: self._rectified, Kind.DETECTIONS: self._detections,
            Kind.RESIDUALS: self._residuals,
            Kind.VIEW_ERROR: self._series, Kind.SCALAR: self._series,
            Kind.STEREO_OFFSET: self._series, Kind.POINT_SERIES: self._series,
            Kind.MASK: self._segmentation, Kind.EDGES: self._segmentation,
            Kind.POINT_2D: self._point_2d, Kind.GROUND_TRUTH: self._ground_truth,
            Kind.TEXT: self._text,
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

    # --- helpers ---------------------------------------------------------------------------

    def _warn(self, key: str, text: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            self.warnings.append(text)

    def _decoded(self, raw: RawMessage, record: type[Decoded]) -> Decoded:
        """The message as the record its route was chosen for (by its type)."""
        message = self._decode(raw)
        assert isinstance(message, record)
        return message

    def _still_image(self, raw: RawMessage) -> Image | CompressedImage:
        """The message of an image route that video never takes."""
        message = self._decode(raw)
        assert isinstance(message, Image | CompressedImage)
        return message

    def _emit(self, entity: str, archetype: Any, *, count: bool = True) -> None:
        self._out.emit(entity, archetype, count=count)

    def _times(self, raw: RawMessage, stamp_ns: int | None) -> None:
        self._out.at(raw.log_time_ns, stamp_ns, self._replay_ns)

    def close(self) -> None:
        """Send what is still pending and stop the encoding threads."""
        self._out.close()
        for topic, (count, why) in sorted(self._failed.items()):
            self.warnings.append(f"{topic}: {count} {why}")

    def _camera_of(self, route: Route, message: Any) -> _Camera | None:
        """The camera a message draws on: named by its route, or found by frame and stamp."""
        if not route.by_frame:
            return self.cameras.get(route.namespace)
        frame_id = getattr(message, "frame_id", "")
        names = self.plan.frames.get(frame_id, [])
        if not names:
            self._warn(f"frame {frame_id}", f"frame_id {frame_id!r} belongs to no camera of "
                                            "the log; its overlays are not shown")
            return None
        stamp = getattr(message, "stamp_ns", None)
        seen = [ns for ns in names if self.cameras[ns].frames.saw(stamp)]
        return self.cameras[(seen or names)[0]]

    def _overlay(self, raw: RawMessage, cam: _Camera, entity: str, stamp_ns: int,
                 archetype: Any) -> None:
        self._emit(entity, archetype)
        image_topic, counts = cam.plan.image_topic, self.plan.counts
        dense = image_topic is not None and counts.get(raw.topic, 0) >= counts.get(image_topic, 0)
        if not dense:
            cam.frames.drawn(entity, stamp_ns)

    def _image(self, raw: RawMessage, route: Route) -> None:
        cam = self.cameras[route.namespace]
        if raw.topic != cam.plan.image_topic:
            return
        message = self._decode(raw)
        sample = video_sample(message)  # rerun decodes video itself: every sample is kept
        if sample is not None:  # once its stream has had a keyframe
            cam.frames.keyframed = cam.frames.keyframed or is_keyframe(message)
            if not cam.frames.keyframed:
                raise EncodingError("a video picture before the stream's first keyframe")
            self._times(raw, getattr(message, "stamp_ns", None))
            self._emit(f"{cam.plan.entity}/video", sample)
            return
        assert isinstance(message, Image | CompressedImage)
        stamp = message.stamp_ns
        if not cam.frames.take(stamp):
            return
        self._times(raw, stamp)
        for entity in cam.frames.stale(stamp, stamp_free_view(raw.data)):
            self._emit(entity, ClearRow(), count=False)
        if isinstance(message, Image):
            cam.size = (message.width, message.height)
        self._emit(f"{cam.plan.entity}/image", self._archetype(message))

    def _archetype(self, message: Image | CompressedImage, draw_order: float | None = None) -> Any:
        return image_archetype(message, self.options.jpeg_quality, self._out.encode,
                               draw_order=draw_order)

    def _camera_info(self, raw: RawMessage, route: Route) -> None:
        cam = self.cameras[route.namespace]
        if route.kind is Kind.CALIBRATED_INFO and cam.plan.info_topic is not None:
            return  # the driver's camera_info draws the camera; calibrated adds the baseline
        key = stamp_free_key(raw.data)
        if key == cam.info_key:
            return
        cam.info_key = key
        info = self._decoded(raw, CameraInfo)
        if info.k[0, 0] <= 0 or info.k[1, 1] <= 0 or info.width <= 0 or info.height <= 0:
            self._warn(raw.topic, f"{raw.topic}: camera_info has no intrinsics; no Pinhole")
            return
        if info.distortion_model in ("plumb_bob", "rational_polynomial", ""):
            try:
                cam.model = CameraModel.from_camera_info(info)
            except ValueError:
                cam.model = None
        cam.size = (info.width, info.height)
        self._times(raw, info.stamp_ns)
        self._emit(cam.plan.entity, rr.Pinhole(
            image_from_camera=info.k, resolution=[info.width, info.height],
            image_plane_distance=self.plan.image_plane_distance_m))

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
        self._overlay(raw, cam, f"{cam.plan.entity}/calibration/detections", stamp,
                      self._archetype(message, draw_order=ORDER_DETECTIONS))
        why = self.plan.rejected.get(cam.plan.namespace, {}).get(stamp)
        if why is not None:
            image = still_frame(message)
            self._overlay(raw, cam, f"{cam.plan.entity}/calibration/status", stamp, rr.Boxes2D(
                mins=[[0, 0]], sizes=[[image.width, image.height]], colors=[RED],
                labels=[f"rejected: {why}"]))

    def _residuals(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, Text)
        view = ViewResiduals.from_message(message)
        cam = self.cameras[route.namespace]
        if not cam.frames.shows(view.stamp_ns):
            return
        self._times(raw, view.stamp_ns)
        base, scale = f"{cam.plan.entity}/calibration", self.options.residual_scale
        self._overlay(raw, cam, f"{base}/corners", view.stamp_ns,
                      self._points(f"{base}/corners", view.corners_px, GREEN, CORNER_RADIUS))
        self._overlay(raw, cam, f"{base}/residuals", view.stamp_ns, rr.Arrows2D(
            origins=view.corners_px, vectors=view.residuals_px * scale, colors=[ORANGE]))
        if cam.size is not None:
            width, height = cam.size
            self._overlay(raw, cam, f"{base}/status", view.stamp_ns, rr.Boxes2D(
                mins=[[0, 0]], sizes=[[width, height]], colors=[GREEN],
                labels=[f"used: view RMS {view.rms_px:.3f} px (residuals ×{scale:g})"]))
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
        self._overlay(raw, cam, f"{cam.plan.entity}/{route.entity}", message.stamp_ns,
                      rr.SegmentationImage(classes, opacity=opacity, draw_order=order))

    def _point_2d(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, PointStamped)
        cam = self._camera_of(route, message)
        if cam is None or not cam.frames.shows(message.stamp_ns):
            return
        self._times(raw, message.stamp_ns)
        entity = f"{cam.plan.entity}/{route.entity}"
        self._overlay(raw, cam, entity, message.stamp_ns, self._points(
            entity, [message.point[:2]], CYAN, CENTROID_RADIUS, label=route.label or None))

    def _ground_truth(self, raw: RawMessage, route: Route) -> None:
        points = self.plan.targets.get(route.detail)
        cam = self.cameras[route.namespace]
        model = cam.model
        if not self.options.ground_truth or points is None or model is None:
            return
        # a target held still sends the same pose again: reuse its projection
        key = stamp_free_key(raw.data)
        last = self._truth.get(raw.topic)
        stamp = header_stamp_ns(raw.data, raw.serialization)
        if last is not None and last[0] == key and last[1] is model and stamp is not None:
            uv = last[2]
        else:
            message = self._decoded(raw, PoseStamped)
            stamp = message.stamp_ns
            uv = inside_image(project_target(
                points, position_m=message.position_m, orientation_xyzw=message.orientation_xyzw,
                model=model), model.width, model.height)
            self._truth[raw.topic] = (key, model, uv)
        if not cam.frames.shows(stamp):
            return
        self._times(raw, stamp)
        entity = f"{cam.plan.entity}/ground_truth/{route.detail}"
        self._overlay(raw, cam, entity, stamp, self._points(entity, uv, YELLOW, TRUTH_RADIUS))

    def _points(self, entity: str, positions: Any, color: tuple[int, int, int], radius: Any,
                label: str | None = None) -> Any:
        """Points2D of the positions; colour, size and label are logged once, static."""
        if entity not in self._styled:
            self._styled.add(entity)
            self.rec.log(entity, rr.Points2D.from_fields(
                colors=[color], radii=radius, labels=None if label is None else [label]),
                static=True)
        return PointsRow(np.asarray(positions, dtype=np.float32))

    def _text(self, raw: RawMessage, route: Route) -> None:
        message = self._decoded(raw, Text)
        indented = reindent_json(message.data)  # None: shown as it is
        text = message.data if indented is None else f"```json\n{indented}\n```"
        self._times(raw, None)
        self._emit(text_entity(raw.topic), rr.TextDocument(text, media_type="text/markdown"))
