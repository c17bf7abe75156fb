"""A board's corners measured again through a first calibration: a second pass over the log.

``cornerSubPix`` is biased where squares are strongly distorted (on a fisheye a field of
0.03-0.05 px outwards, which the solver reads as a lens), and ChArUco corners are refined in
small windows between the markers (which boards and lenses:
:func:`processors.calibration.corners.remeasures`). Once a first solve has given
every camera a model and every view a board pose, each view's image is read again and its
corners measured on the board plane (:func:`processors.calibration.corners.refine_on_board`);
a held pose's frames are averaged into one image first (they show the same board, so the
measurement is made once, on less noise). Corners that cannot be measured so keep the
detector's position.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor, wait

import numpy as np

from processors.calibration.board import Board
from processors.calibration.corners import edge_band_m, refine_on_board
from processors.calibration.joint import BoardView, JointResult
from replay.formats import LogReader
from replay.messages import F64
from replay.progress import progress_bar

from .instants import ViewsOfRig
from .pixels import TopicFrames
from .views import CameraViews

__all__ = ["remeasured_rig"]


def _remeasured(view: BoardView, image: np.ndarray, joint: JointResult, board: Board, *,
                instant: int) -> F64:
    """The view's corners measured again through its camera and the board pose the solve
    gave it (``instant``: its own, when it was not simultaneous with its instant's views)."""
    model = joint.models[view.camera]
    camera_from_board = joint.camera_from_reference[view.camera] \
        @ joint.reference_from_board[instant]
    refined, ok = refine_on_board(image, model, camera_from_board,
                                  board.points_in_board()[view.point_ids], board.square_m,
                                  band_m=edge_band_m(board))
    return np.where(ok[:, None], refined, view.corners_px)


def remeasured_rig(reader: LogReader, cameras: list[CameraViews], rig: ViewsOfRig,
                   joint: JointResult, board: Board, *, workers: int,
                   progress: bool | None = False) -> ViewsOfRig:
    """``rig`` with the corners of every view ``joint`` used measured again on the board
    plane, through ``joint``'s models and board poses (one pass over ``reader``'s images,
    with a bar unless ``progress`` is False; None: on a terminal)."""
    by_topic = {c.source.image_topic: camera for camera, c in enumerate(cameras)}
    # camera -> frame index -> the view it belongs to
    view_of: list[dict[int, int]] = [{} for _ in cameras]
    for index, (board_view, frames) in enumerate(zip(rig.views, rig.frames_of, strict=True)):
        if index not in joint.rejected \
                and joint.views[index].instant in joint.reference_from_board:
            for frame in frames:
                view_of[board_view.camera][frame] = index
    counters = [0] * len(cameras)
    sums: dict[int, tuple[np.ndarray, int]] = {}  # view -> (sum of its images, how many)
    pending: dict[int, Future[F64]] = {}
    in_flight: deque[Future[F64]] = deque()  # at most two per worker: bounds the images held
    to_frame = TopicFrames()
    bar = progress_bar(total=sum(reader.topics[topic].count for topic in by_topic),
                       unit="frame", desc="measure corners again", progress=progress)
    with ThreadPoolExecutor(max_workers=workers) as pool, bar:

        def submit(view: int, gray: np.ndarray) -> None:
            pending[view] = future = pool.submit(_remeasured, rig.views[view], gray, joint,
                                                 board, instant=joint.views[view].instant)
            in_flight.append(future)
            while len(in_flight) > 2 * workers:
                wait([in_flight.popleft()])

        for raw in reader.raw_messages(list(by_topic)):
            bar.update()
            camera = by_topic[raw.topic]
            image = to_frame(reader, raw)
            if image is None:  # no frame in the views either (see TopicFrames)
                continue
            frame = counters[camera]
            counters[camera] += 1
            view = view_of[camera].get(frame)
            if view is None:
                continue
            gray = image.mono8()
            held = len(rig.frames_of[view])
            if held == 1:
                submit(view, gray)
                continue
            total, count = sums.get(view, (np.zeros(gray.shape, np.float32), 0))
            total += gray
            if count + 1 < held:
                sums[view] = (total, count + 1)
                continue
            sums.pop(view, None)
            submit(view, total / held)
        corners = {view: future.result() for view, future in pending.items()}
    views = [dataclasses.replace(v, corners_px=corners[i]) if i in corners else v
             for i, v in enumerate(rig.views)]
    return ViewsOfRig(views, rig.frames_of, rig.pairs, rig.candidates, rig.frame_scatter_px)
