"""plan_optics: the ideal render MuJoCo makes and the warp to the camera's model."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from recorder.errors import ScenarioError
from recorder.optics import Optics, plan_optics
from replay.camera import CameraModel
from replay.messages import F64

W, H, HFOV_RAD = 320, 240, 0.6


def model(*, fx: float | None = None, fy: float | None = None, cx: float | None = None,
          cy: float | None = None, distortion_model: str = "plumb_bob",
          d: list[float] | None = None) -> CameraModel:
    f = (W / 2) / math.tan(HFOV_RAD / 2)
    k = np.array([[fx or f, 0, (W - 1) / 2 if cx is None else cx],
                  [0, fy or f, (H - 1) / 2 if cy is None else cy], [0, 0, 1]])
    return CameraModel(W, H, k, distortion_model, np.array(d or [0.0]))


def test_ideal_camera_renders_directly() -> None:
    camera = model()
    optics = plan_optics(camera, 1)
    assert optics.map_x is None and optics.map_y is None
    assert (optics.render_width, optics.render_height) == (W, H)
    # MuJoCo's fovy spans the image height: pixel rows -0.5 .. H - 0.5
    fovy_deg = math.degrees(2 * math.atan((H / 2) / camera.fy))
    assert optics.fovy_deg == pytest.approx(fovy_deg, abs=1e-12)
    # square pixels: the same focal length across, from the horizontal FOV
    assert (W / 2) / math.tan(HFOV_RAD / 2) == pytest.approx(
        (H / 2) / math.tan(math.radians(optics.fovy_deg) / 2))
    rendered = np.random.default_rng(0).integers(0, 256, (H, W, 3), dtype=np.uint8)
    assert optics.apply(rendered) is rendered


def ideal_rays(optics: Optics) -> F64:
    """Normalized ideal coordinates (N, 2) of every output pixel's ray, from the render
    geometry (the maps read the box-filtered render, shifted by its anchor)."""
    assert optics.map_x is not None and optics.map_y is not None
    f_render = (optics.render_height / 2) / math.tan(math.radians(optics.fovy_deg) / 2)
    cx = (optics.render_width - 1) / 2 + optics.box_offset_px
    cy = (optics.render_height - 1) / 2 + optics.box_offset_px
    x = (optics.map_x.astype(np.float64) - cx) / f_render
    y = (optics.map_y.astype(np.float64) - cy) / f_render
    return np.column_stack([x.ravel(), y.ravel()])


def pixel_centres() -> F64:
    """Output pixel centres (N, 2), row-major."""
    grid_u, grid_v = np.meshgrid(np.arange(W, dtype=np.float64), np.arange(H, dtype=np.float64))
    return np.column_stack([grid_u.ravel(), grid_v.ravel()])


def supersampled_reference(optics: Optics, camera: CameraModel, rendered: np.ndarray) -> F64:
    """The definition the warp implements: the mean of s x s bilinear samples of the render
    at the ideal rays of each output pixel's sub-pixel centres (float, no rounding)."""
    s = optics.supersample
    f_render = (optics.render_height / 2) / math.tan(math.radians(optics.fovy_deg) / 2)
    us = (np.arange(W * s) + 0.5) / s - 0.5
    vs = (np.arange(H * s) + 0.5) / s - 0.5
    grid_u, grid_v = np.meshgrid(us, vs)
    xy = camera.undistort_pixels(np.column_stack([grid_u.ravel(), grid_v.ravel()]))
    map_x = (f_render * xy[:, 0] + (optics.render_width - 1) / 2).reshape(H * s, W * s)
    map_y = (f_render * xy[:, 1] + (optics.render_height - 1) / 2).reshape(H * s, W * s)
    samples = cv2.remap(rendered.astype(np.float32), map_x.astype(np.float32),
                        map_y.astype(np.float32), cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_REPLICATE)
    return np.asarray(samples.reshape(H, s, W, s, -1).mean(axis=(1, 3)), dtype=np.float64)


WARPED = {
    "plumb_bob": model(d=[-0.2, 0.05, 0.001, -0.001, 0.0]),
    "rational_polynomial": model(distortion_model="rational_polynomial",
                                 d=[-0.25, 0.06, 0.0, 0.0, 0.0, 0.05, 0.0, 0.0]),
    "intrinsics": model(fx=500.0, fy=540.0, cx=170.0, cy=110.0),
}
#: (case, supersample); the ideal camera is never remapped (see the box-filter tests)
WARP_PARAMS = [(case, s) for case in sorted(WARPED) for s in (1, 2)]


@pytest.mark.parametrize("s", [1, 2, 3])
def test_ideal_camera_is_an_exact_denser_render(s: int) -> None:
    camera = model()
    optics = plan_optics(camera, s)
    assert optics.map_x is None and optics.map_y is None
    assert (optics.render_width, optics.render_height) == (W * s, H * s)
    f_render = (optics.render_height / 2) / math.tan(math.radians(optics.fovy_deg) / 2)
    assert f_render == pytest.approx(s * camera.fy, rel=1e-12)


def test_box_filter_keeps_pixel_footprints_aligned() -> None:
    """Render pixels s*u .. s*u+s-1 make output pixel u: an edge on a block boundary of the
    render stays a sharp edge between two output pixels, with no bleed."""
    s = 2
    optics = plan_optics(model(), s)
    rendered = np.zeros((H * s, W * s, 3), np.uint8)
    rendered[:, s * 100:] = 240  # edge at the boundary between output columns 99 and 100
    rendered[s * 50 + 1:, :, 1] = 120  # edge inside output row 50: that row averages
    image = optics.apply(rendered)
    assert image.shape == (H, W, 3)
    assert (image[:, :100, 0] == 0).all() and (image[:, 100:, 0] == 240).all()
    assert (image[:50, :100, 1] == 0).all()
    assert image[50, 0, 1] == 60 and image[51, 0, 1] == 120


@pytest.mark.parametrize(("case", "s"), WARP_PARAMS)
def test_every_map_sample_comes_from_its_ideal_ray(case: str, s: int) -> None:
    camera = WARPED[case]
    optics = plan_optics(camera, s)
    assert optics.supersample == s
    assert optics.output_size == (W, H)
    assert optics.map_x is not None and optics.map_y is not None
    assert optics.map_x.shape == optics.map_y.shape == (H, W)
    # every footprint, box filter included, lies inside the render: no border is replicated
    reach = s / 2 + 1
    assert optics.map_x.min() >= reach and optics.map_x.max() <= optics.render_width - 1 - reach
    assert optics.map_y.min() >= reach and optics.map_y.max() <= optics.render_height - 1 - reach
    redistorted = camera.distort_normalized(ideal_rays(optics))
    error = np.abs(redistorted - pixel_centres()).max()
    assert error < 1e-3


@pytest.mark.parametrize(("s", "exact"), [(2, True), (3, True), (2, False)])
def test_warp_is_the_mean_of_supersampled_bilinear_samples(s: int, exact: bool) -> None:
    """Where the footprint is one render pixel per sub-sample (a shifted principal point),
    box filter + one sample equals the s x s samples' mean; through a k1 = -0.2 lens only
    the averaging width changes, a little."""
    camera = model(cx=331.25, cy=228.5) if exact else model(d=[-0.2, 0.05, 0.0, 0.0, 0.0])
    optics = plan_optics(camera, s)
    rng = np.random.default_rng(s)
    coarse = rng.integers(0, 256, (optics.render_height // 8 + 2, optics.render_width // 8 + 2,
                                   3)).astype(np.uint8)
    rendered = cv2.resize(coarse, (optics.render_width, optics.render_height),
                          interpolation=cv2.INTER_CUBIC)  # detail at a few render pixels
    reference = supersampled_reference(optics, camera, rendered)
    # in float, so that only the method differs (a 0.25 render px shift would differ by ~2.6)
    image = optics.apply(rendered.astype(np.float32)).astype(np.float64)
    difference = np.abs(image - reference)
    if exact:
        assert difference.max() < 1e-3
    else:
        assert difference.mean() < 0.1 and np.percentile(difference, 99) < 0.5
    # the uint8 images a recording writes differ from it by rounding only
    rounded = np.abs(optics.apply(rendered).astype(np.float64) - image)
    assert rounded.max() < 2.0 and rounded.mean() < 0.5


def test_warp_output_has_the_camera_size() -> None:
    optics = plan_optics(WARPED["plumb_bob"], 2)
    rendered = np.full((optics.render_height, optics.render_width, 3), 200, np.uint8)
    image = optics.apply(rendered)
    assert image.shape == (H, W, 3) and image.dtype == np.uint8
    assert (image == 200).all()


def test_barrel_distortion_needs_a_wider_render() -> None:
    """k1 < 0 pulls the image corners in, so the ideal view must reach further out."""
    plain = plan_optics(model(), 2)
    barrel = plan_optics(WARPED["plumb_bob"], 2)
    assert barrel.render_width > plain.render_width
    assert barrel.fovy_deg > plain.fovy_deg


def test_non_invertible_distortion_is_rejected() -> None:
    k1 = -5.0
    # r_d = r (1 + k1 r^2) peaks at r = 1 / sqrt(-3 k1); image points beyond that peak have
    # no undistorted ray
    r = 1 / math.sqrt(-3 * k1)
    peak = r * (1 + k1 * r * r)
    f = (W / 2) / math.tan(HFOV_RAD / 2)
    corner = math.hypot((W / 2) / f, (H / 2) / f)
    assert corner > peak
    with pytest.raises(ScenarioError, match="not invertible"):
        plan_optics(model(d=[k1, 0.0, 0.0, 0.0, 0.0]), 2)
