"""A chessboard imaged without noise, and what camlog's corner refinements make of it.

The image is the exact footprint average of the board over each pixel (``supersample`` x
``supersample`` rays per pixel through the camera model, each ray shaded by the square it
hits: dark 30, bright 220, the margin bright), quantised to 8 bits like a camera's. The
corners are then refined as :func:`processors.calibration.detect.track_chessboard` refines
them, from their true projections; the difference is the refinement's own error, with no
pixel noise at all. :func:`board_plane_error_px` measures the refinement on the board plane
(:mod:`processors.calibration.corners`) the same way, guided by the true model and pose or by
slightly wrong ones.

Run as a script it compares the two on the calibration scenarios' cameras (the pinhole
``mono_checkerboard``, the distorted ``mono_heldout``, the ``mono_fisheye``), the board tilted
0-60 degrees at nine places across the image, and prints per camera and tilt the RMS of the
error and its bias: the mean error, and its mean component towards the principal point.

    python -m benchmarks.ideal_board [--poses 4] [--supersample 8]
"""

from __future__ import annotations

import argparse
import dataclasses

import cv2
import numpy as np

from processors.calibration.board import Board
from processors.calibration.corners import refine_on_board
from processors.calibration.detect import track_chessboard
from replay.camera import CameraModel
from replay.messages import F64

DARK, BRIGHT = 30.0, 220.0
#: pixels rendered around the board's corners (the refinement window and the margin squares)
PAD_PX = 40


def ideal_image(model: CameraModel, camera_from_board: F64, board: Board, *,
                supersample: int = 4, marker_m: float = 0.0) -> np.ndarray:
    """``(H, W)`` uint8 image of a chessboard at ``camera_from_board`` ``(4, 4)``; only the
    pixels near the board are rendered (the rest is mid grey). ``marker_m`` > 0 puts a dark
    square that wide in the middle of every bright square (a ChArUco board's markers, as
    their black outlines show them to a corner's refinement)."""
    rotation, translation = camera_from_board[:3, :3], camera_from_board[:3, 3]
    points = board.points_in_board()
    corners_px = model.project(points @ rotation.T + translation)
    low = np.maximum(np.floor(corners_px.min(axis=0)) - PAD_PX, 0).astype(int)
    high = np.minimum(np.ceil(corners_px.max(axis=0)) + PAD_PX,
                      [model.width - 1, model.height - 1]).astype(int)
    image = np.full((model.height, model.width), 128.0)
    us, vs = np.meshgrid(np.arange(low[0], high[0] + 1), np.arange(low[1], high[1] + 1))
    offsets = (np.arange(supersample) + 0.5) / supersample - 0.5
    sub = np.stack(np.meshgrid(offsets, offsets), axis=-1).reshape(-1, 2)
    pixels = (np.stack([us, vs], axis=-1)[:, :, None, :] + sub).reshape(-1, 2)
    rays = model.pixel_rays(pixels)
    normal = rotation[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = (translation @ normal) / (rays @ normal)
    in_board = (rays * depth[:, None] - translation) @ rotation
    step_x = (points[1] - points[0]) / board.square_m
    step_y = (points[board.cols] - points[0]) / board.square_m
    a = (in_board - points[0]) @ step_x / board.square_m
    b = (in_board - points[0]) @ step_y / board.square_m
    hit = np.isfinite(depth) & (depth > 0)
    on_squares = hit & (a > -1) & (a < board.cols) & (b > -1) & (b < board.rows)
    dark = (np.floor(a) + np.floor(b)) % 2 == 0
    if marker_m > 0:
        half = marker_m / (2 * board.square_m)
        dark |= (np.abs(a - np.floor(a) - 0.5) < half) & (np.abs(b - np.floor(b) - 0.5) < half)
    shade = np.where(on_squares & dark, DARK, BRIGHT)
    shade[~hit] = 128.0
    image[low[1]:high[1] + 1, low[0]:high[0] + 1] = \
        shade.reshape(*us.shape, supersample * supersample).mean(axis=-1)
    quantised: np.ndarray = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    return quantised


def refinement_error_px(model: CameraModel, camera_from_board: F64, board: Board, *,
                        supersample: int = 4, image: np.ndarray | None = None) -> F64 | None:
    """Refined minus true corners ``(N, 2)`` in board order on the ideal image (or ``image``,
    already rendered), None when the refinement rejects the view (e.g. a board at the image
    border)."""
    points = board.points_in_board()
    true_px = model.project(points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
    if image is None:
        image = ideal_image(model, camera_from_board, board, supersample=supersample)
    found = track_chessboard(image, true_px, board)
    if found is None:
        return None
    refined = found.corners_px
    if np.abs(refined[0] - true_px[0]).sum() > np.abs(refined[0] - true_px[-1]).sum():
        refined = refined[::-1]  # put back in board order
    return np.asarray(refined - true_px)


def board_plane_error_px(model: CameraModel, camera_from_board: F64, board: Board, *,
                         guide: CameraModel | None = None, guide_pose: F64 | None = None,
                         supersample: int = 4, image: np.ndarray | None = None) -> F64 | None:
    """Board-plane refinement minus true corners ``(N, 2)`` on the ideal image (or
    ``image``), the patches laid by ``guide`` at ``guide_pose`` (default: the true model and
    pose); None when a corner was not measured."""
    points = board.points_in_board()
    true_px = model.project(points @ camera_from_board[:3, :3].T + camera_from_board[:3, 3])
    if image is None:
        image = ideal_image(model, camera_from_board, board, supersample=supersample)
    refined, ok = refine_on_board(image, guide or model, camera_from_board
                                  if guide_pose is None else guide_pose, points, board.square_m)
    if not ok.all():
        return None
    return np.asarray(refined - true_px)


@dataclasses.dataclass(frozen=True)
class Camera:
    """A scenario's camera and the board it sees, ``distance_m`` away."""

    name: str
    model: CameraModel
    board: Board
    distance_m: tuple[float, float]


def _rotation(rvec: F64) -> F64:
    return np.asarray(cv2.Rodrigues(np.asarray(rvec, dtype=np.float64))[0])


def tilted_pose(model: CameraModel, board: Board, at_px: F64, distance_m: float, *,
                tilt_rad: float, rng: np.random.Generator) -> F64:
    """``camera_from_board`` ``(4, 4)``: the board's centre on the ray of ``at_px``, facing
    the camera along it, then tilted by ``tilt_rad`` about a random in-plane axis and rolled
    at random."""
    ray = model.pixel_rays(np.asarray(at_px, dtype=np.float64)[None])[0]
    z = ray
    x = np.cross([0.0, 1.0, 0.0], z)
    x /= np.linalg.norm(x)
    facing = np.column_stack([x, np.cross(z, x), z])
    angle = rng.uniform(0, 2 * np.pi)
    tilt = _rotation(tilt_rad * np.array([np.cos(angle), np.sin(angle), 0.0]))
    roll = _rotation(np.array([0.0, 0.0, rng.uniform(-np.pi, np.pi)]))
    centre = np.array([(board.cols - 1) / 2, (board.rows - 1) / 2, 0.0]) * board.square_m
    out = np.eye(4)
    out[:3, :3] = facing @ tilt @ roll
    out[:3, 3] = ray * distance_m - out[:3, :3] @ centre
    return out


def _inside(model: CameraModel, pose: F64, board: Board, margin_px: float = 16.0) -> bool:
    corners = board.points_in_board() @ pose[:3, :3].T + pose[:3, 3]
    if (corners[:, 2] <= 0).any() and not model.is_fisheye:
        return False
    uv = model.project(corners)
    return bool((uv >= margin_px).all() and (uv[:, 0] <= model.width - 1 - margin_px).all()
                and (uv[:, 1] <= model.height - 1 - margin_px).all())


def perturbed(model: CameraModel, rng: np.random.Generator) -> CameraModel:
    """The model a first calibration might give: focal lengths 0.05 %, the principal point
    0.5 px and every distortion coefficient 2 % off."""
    k = model.k.copy()
    k[0, 0] *= 1 + 5e-4 * rng.choice([-1, 1])
    k[1, 1] *= 1 + 5e-4 * rng.choice([-1, 1])
    k[:2, 2] += 0.5 * rng.choice([-1, 1], 2)
    d = model.d * (1 + 0.02 * rng.choice([-1, 1], len(model.d)))
    return dataclasses.replace(model, k=k, d=d)


def nudged(pose: F64, rng: np.random.Generator) -> F64:
    """``pose`` turned by 0.05 degrees and moved by 0.2 mm."""
    out = pose.copy()
    out[:3, :3] = _rotation(rng.normal(size=3) * np.radians(0.05) / np.sqrt(3)) @ pose[:3, :3]
    out[:3, 3] += rng.normal(size=3) * 2e-4 / np.sqrt(3)
    return out


def cameras() -> list[Camera]:
    """The calibration scenarios' cameras with their boards and distances."""
    from recorder.scenario import load_scenario  # the recorder only for this script

    out = []
    for name, square_m, distance_m in (("mono_checkerboard", 0.01, (0.15, 0.25)),
                                       ("mono_heldout", 0.01, (0.15, 0.32)),
                                       ("mono_fisheye", 0.015, (0.09, 0.16))):
        model = load_scenario(name).cameras[0].model
        out.append(Camera(name, model, Board(7, 6, square_m), distance_m))
    return out


def compare(camera: Camera, tilt_rad: float, poses: int, *, supersample: int,
            seed: int = 0) -> str:
    """One table row: RMS and bias of cornerSubPix and of the board-plane refinement (true
    guide, then a perturbed one) over ``poses`` poses at each of nine places."""
    rng = np.random.default_rng(seed)
    model = camera.model
    places = [(model.width * fx, model.height * fy) for fy in (0.2, 0.5, 0.8)
              for fx in (0.2, 0.5, 0.8)]
    errors: list[list[F64]] = [[], [], []]
    where: list[F64] = []
    for at_px in places:
        made = 0
        for _ in range(50 * poses):
            if made == poses:
                break
            pose = tilted_pose(model, camera.board, np.asarray(at_px),
                               rng.uniform(*camera.distance_m), tilt_rad=tilt_rad, rng=rng)
            if not _inside(model, pose, camera.board):
                continue
            image = ideal_image(model, pose, camera.board, supersample=supersample)
            found = [refinement_error_px(model, pose, camera.board, image=image),
                     board_plane_error_px(model, pose, camera.board, image=image),
                     board_plane_error_px(model, pose, camera.board, image=image,
                                          guide=perturbed(model, rng),
                                          guide_pose=nudged(pose, rng))]
            if any(f is None for f in found):
                continue
            for store, error in zip(errors, found, strict=True):
                store.append(np.asarray(error))
            points = camera.board.points_in_board()
            where.append(model.project(points @ pose[:3, :3].T + pose[:3, 3]))
            made += 1
    if not where:
        return f"| {camera.name} | {np.degrees(tilt_rad):.0f} | no pose fits |"
    at = np.concatenate(where)
    inwards = np.array([model.cx, model.cy]) - at
    inwards /= np.maximum(np.linalg.norm(inwards, axis=1, keepdims=True), 1e-9)
    cells = []
    for store in errors:
        e = np.concatenate(store)
        mean = e.mean(axis=0)
        inward = float(np.mean(np.sum(e * inwards, axis=1)))
        cells.append(f"{np.sqrt(np.mean(np.sum(e ** 2, axis=1))):.4f} / "
                     f"({mean[0]:+.4f}, {mean[1]:+.4f}) / {inward:+.4f}")
    return (f"| {camera.name} | {np.degrees(tilt_rad):.0f} | {len(where)} | "
            + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=4, help="poses per place and tilt")
    parser.add_argument("--supersample", type=int, default=8,
                        help="rays per pixel side of the rendering (default 8)")
    args = parser.parse_args()
    print("| camera | tilt (°) | views | cornerSubPix: RMS / mean (u, v) / inwards (px) | "
          "board plane, true guide | board plane, perturbed guide |")
    print("| --- | --- | --- | --- | --- | --- |")
    for camera in cameras():
        for tilt_deg in (0, 20, 40, 60):
            print(compare(camera, np.radians(tilt_deg), args.poses,
                          supersample=args.supersample), flush=True)


if __name__ == "__main__":
    main()
