"""How a camera itself is drawn, and the helpers every handler of the scene logger shares.

:class:`CameraDrawing` is the base of :class:`~rerun_export.logger.SceneLogger`: the state of
each camera (:class:`CameraState`), the emitter that sends each log call at its message's
times, overlays that go with their frame, and a camera's own messages: its camera_info (a
``Pinhole``, or the pinhole views of a lens that is not a pinhole, :mod:`rerun_export.lens`,
with the camera model in full, :mod:`rerun_export.camera_records`), its images (remapped to
its views on the worker threads) and the simulator's targets seen through its lens (in 2D on
the raw image, and in 3D under a camera shown through views, where rerun projects them).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np
import rerun as rr

from replay.camera import CameraModel
from replay.errors import EncodingError
from replay.formats.base import RawMessage
from replay.frames import decode_frame
from replay.messages import CameraInfo, CompressedImage, Image, Message, PoseStamped
from replay.pinhole_views import is_pinhole

from .camera_records import camera_info_archetype, pinhole_view_archetype, same_model
from .columns import ClearRow, PointsRow
from .emitter import Emitter, Flush
from .frames import CameraFrames
from .images import image_archetype, is_keyframe, video_sample
from .lens import VIEW_PLANE_DEPTHS, Lens, views_of
from .options import LoggerOptions
from .overlays import (
    header_stamp_ns,
    inside_image,
    project_target,
    stamp_free_key,
    stamp_free_view,
    target_in_camera,
)
from .scene import CameraPlan, ScenePlan
from .topics import Route

__all__ = ["CameraDrawing", "CameraState"]

Decoded = TypeVar("Decoded")

#: draw orders: overlays above the image, the annotated calibration image between
ORDER_DETECTIONS, ORDER_MASK, ORDER_EDGES = -9.0, -8.0, -7.0
GREEN, ORANGE, RED, YELLOW, CYAN = (60, 230, 60), (255, 150, 0), (255, 50, 50), (255, 230, 0), \
    (0, 220, 255)
CORNER_RADIUS, CENTROID_RADIUS, TRUTH_RADIUS, GUIDE_RADIUS = (
    rr.components.Radius.ui_points(r) for r in (2.5, 5.0, 1.5, 0.5))


@dataclass
class CameraState:
    """Logging state of one camera."""

    plan: CameraPlan
    info_key: bytes | None = None
    model: CameraModel | None = None  # for projecting ground truth
    size: tuple[int, int] | None = None  # (width, height) from camera_info or raw images
    frames: CameraFrames = field(default_factory=CameraFrames)
    lens: Lens | None = None  # the pinhole views of a camera shown through them
    remapped: Lens | None = None  # the lens the last view images were made with
    plane_depth_m: float | None = None  # where the views' image planes were put last

    @property
    def shown_through_views(self) -> bool:
        """Whether the camera's raw images are remapped to pinhole views."""
        return bool(self.plan.views)


class CameraDrawing:
    """Logs a camera's own messages to ``rec``, following ``plan``; counts what it logged.
    ``columns``: send images, points and clears in columns of several frames (an export;
    a live replay sends each frame as it comes)."""

    def __init__(self, rec: rr.RecordingStream, plan: ScenePlan, options: LoggerOptions,
                 *, decode: Callable[[RawMessage], Message], flush: Flush = None,
                 columns: bool = False) -> None:
        self.rec, self.plan, self.options, self._decode = rec, plan, options, decode
        # rerun's own log_time (the export's wall clock) and log_tick would clutter timelines
        rec.set_log_time_enabled(False)
        rec.set_log_tick_enabled(False)
        self.cameras = {ns: CameraState(cam, frames=CameraFrames(every=options.every))
                        for ns, cam in plan.cameras.items()}
        lenses = any(cam.views for cam in plan.cameras.values())
        encoders = 2 if options.jpeg_quality is not None or lenses else 0
        self._out = Emitter(rec, encoders=encoders, flush=flush,  # flush: the sink's
                            columns=columns)
        self.counts = self._out.counts  # entity -> logged rows
        self.images = 0  # raw images logged
        self.remapped = 0  # images of pinhole views logged
        self.warnings: list[str] = []
        self._warned: set[str] = set()
        self._failed: dict[str, tuple[int, str]] = {}  # topic -> messages not shown, why
        self._styled: set[str] = set()  # point entities whose colour and size are logged
        # topic -> the last pose, the model it was projected with, pixels, points in camera
        self._truth: dict[str, tuple[bytes, CameraModel, Any, Any]] = {}
        self._replay_ns: int | None = None

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

    def _camera_of(self, route: Route, message: Any) -> CameraState | None:
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

    def _overlay(self, raw: RawMessage, cam: CameraState, entity: str, stamp_ns: int,
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
        content = stamp_free_view(raw.data)
        # before its first camera_info; a pinhole camera has no lens to go through (no view,
        # no content compared, its uncertainty map under its own Pinhole)
        if cam.lens is None and cam.plan.info is not None and cam.shown_through_views:
            cam.lens = Lens.of(cam.plan.info, cam.plan.views)
        # a view image stays until the next one: a raw image that repeats the last (a held
        # pose without sensor noise) needs none of its own
        remap = cam.lens is not None and not (cam.remapped is cam.lens
                                              and cam.frames.repeats(content))
        for entity in cam.frames.stale(stamp, content):
            self._emit(entity, ClearRow(), count=False)
        if isinstance(message, Image):
            cam.size = (message.width, message.height)
        self._emit(f"{cam.plan.raw_entity}/image", self._archetype(message))
        self.images += 1
        if remap and cam.lens is not None:
            self._remap(cam, cam.lens, message)

    def _remap(self, cam: CameraState, lens: Lens, message: Image | CompressedImage) -> None:
        """The raw image remapped to each of the camera's views, on the worker threads."""
        # a raw image is decoded here once (a view of its buffer for most encodings)
        source = decode_frame(message) if isinstance(message, Image) else message
        for index, view in enumerate(lens.views):
            self._emit(f"{cam.plan.entity}/{view.name}/image", self._out.encode(
                lens.remap, source, index, jpeg_quality=self.options.jpeg_quality))
            self.remapped += 1
        cam.remapped = lens

    def _archetype(self, message: Image | CompressedImage, draw_order: float | None = None) -> Any:
        return image_archetype(message, self.options.jpeg_quality, self._out.encode,
                               draw_order=draw_order)

    def _camera_info(self, raw: RawMessage, route: Route) -> None:
        cam = self.cameras[route.namespace]
        if raw.topic != cam.plan.info_topics[0]:
            return  # the calibrated camera_info draws the camera when the log has one
        key = stamp_free_key(raw.data)
        if key == cam.info_key:
            return
        cam.info_key = key
        info = self._decoded(raw, CameraInfo)
        if info.k[0, 0] <= 0 or info.k[1, 1] <= 0 or info.width <= 0 or info.height <= 0:
            self._warn(raw.topic, f"{raw.topic}: camera_info has no intrinsics; no Pinhole")
            return
        try:
            cam.model = CameraModel.from_camera_info(info)
        except (KeyError, ValueError):
            cam.model = None  # a lens model camlog does not know: no ground truth drawn
        cam.size = (info.width, info.height)
        self._times(raw, info.stamp_ns)
        self._emit(cam.plan.entity, camera_info_archetype(info))
        if cam.shown_through_views and cam.model is not None:
            self._views(cam, info)
            return
        if cam.shown_through_views or (not is_pinhole(info) and self.plan.undistorted):
            self._warn(f"lens {raw.topic}", f"{raw.topic}: the {info.distortion_model!r} lens "
                       "is drawn in 3D as a pinhole of its K, its images not undistorted")
        self._emit(cam.plan.entity, rr.Pinhole(
            image_from_camera=info.k, resolution=[info.width, info.height],
            image_plane_distance=self.plan.image_plane_distance_m))

    def _views(self, cam: CameraState, info: CameraInfo) -> None:
        """The camera's pinhole views for a new model (their maps made once here)."""
        before = {view.name for view in cam.lens.views} if cam.lens is not None else set()
        if cam.lens is None or not same_model(info, cam.lens.info):
            planned = cam.plan.info is not None and same_model(info, cam.plan.info)
            cam.lens = Lens.of(info, cam.plan.views if planned
                               else views_of(info, self.plan.undistorted or 1.0))
        views = cam.lens.views
        cam.plane_depth_m = None  # the views' Pinholes below put the planes back
        for gone in sorted(before - {view.name for view in views}):
            self._emit(f"{cam.plan.entity}/{gone}", rr.Clear(recursive=True), count=False)
        for view in views:
            entity = f"{cam.plan.entity}/{view.name}"
            self._emit(entity, rr.Transform3D(mat3x3=view.rotation.T), count=False)
            self._emit(entity, rr.Pinhole(
                image_from_camera=view.k, resolution=[view.width, view.height],
                image_plane_distance=self.plan.image_plane_distance_m
                * VIEW_PLANE_DEPTHS.get(view.name, 1.0)))
            self._emit(entity, pinhole_view_archetype(view), count=False)

    def _board_plane(self, cam: CameraState, in_camera_m: Any) -> None:
        """The image plane of each of the camera's views at the depth of a board it shows in
        3D (median over its points), from this time on: the board's points then lie on the
        view's image where it shows them, seen from any eye and not only from the camera's
        centre."""
        depths = np.asarray(in_camera_m, dtype=np.float64).reshape(-1, 3)[:, 2]
        depths = depths[np.isfinite(depths) & (depths > 0)]
        if cam.lens is None or not len(depths):
            return
        depth = float(np.median(depths))
        if depth == cam.plane_depth_m:  # a board held still: the planes stay where they are
            return
        cam.plane_depth_m = depth
        for view in cam.lens.views:
            self._emit(f"{cam.plan.entity}/{view.name}", rr.Pinhole.from_fields(
                image_plane_distance=depth * VIEW_PLANE_DEPTHS.get(view.name, 1.0)),
                count=False)

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
            uv, in_camera = last[2], last[3]
        else:
            message = self._decoded(raw, PoseStamped)
            stamp = message.stamp_ns
            pose = {"position_m": message.position_m,
                    "orientation_xyzw": message.orientation_xyzw}
            uv = inside_image(project_target(points, model=model, **pose), model.width,
                              model.height)
            in_camera = target_in_camera(points, **pose)
            self._truth[raw.topic] = (key, model, uv, in_camera)
        if not cam.frames.shows(stamp):
            return
        self._times(raw, stamp)
        entity = f"{cam.plan.raw_entity}/ground_truth/{route.detail}"
        self._overlay(raw, cam, entity, stamp, self._points(entity, uv, YELLOW, TRUTH_RADIUS))
        if cam.shown_through_views:  # in 3D too, where rerun projects it onto the views
            entity = f"{cam.plan.entity}/ground_truth/{route.detail}"
            self._overlay(raw, cam, entity, stamp, self._points(entity, in_camera, YELLOW,
                                                                TRUTH_RADIUS, dimension=3))
            if cam.plan.calibrated_info_topic is None:  # else the solved board sets it
                self._board_plane(cam, in_camera)

    def _points(self, entity: str, positions: Any, color: tuple[int, int, int], radius: Any,
                label: str | None = None, *, dimension: int = 2) -> Any:
        """Points2D (Points3D) of the positions; colour, size and label are logged once,
        static."""
        if entity not in self._styled:
            self._styled.add(entity)
            archetype = rr.Points3D if dimension == 3 else rr.Points2D
            self.rec.log(entity, archetype.from_fields(
                colors=[color], radii=radius, labels=None if label is None else [label]),
                static=True)
        return PointsRow(np.asarray(positions, dtype=np.float32).reshape(-1, dimension))
