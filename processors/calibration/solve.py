"""Intrinsic calibration of one camera: OpenCV's solver, outlier rejection, uncertainty.

Options keep camera_calibration's meaning: ``fix_principal_point`` holds (cx, cy) at the
image centre, ``fix_aspect_ratio`` forces fx = fy, and ``k_coefficients`` radial terms are
estimated (<= 3: plumb_bob, > 3: rational_polynomial, up to 6). Tangential distortion
(p1, p2) is held at zero (``"zero"``, camera_calibration's --zero-tangent-dist), always
estimated (``"estimate"``, camera_calibration's default) or, by default (``"auto"``),
estimated only when the views show it: a likelihood-ratio test of the two fits. At a narrow
field of view p1, p2 trade almost freely against the principal point and a small turn of
the camera, so estimating them when the lens has none costs principal point accuracy.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError

#: order of OpenCV's stdDeviationsIntrinsics
STD_NAMES = ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")
#: a view whose RMS exceeds max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX) is rejected
OUTLIER_FACTOR = 3.0
OUTLIER_FLOOR_PX = 0.3
MIN_VIEWS = 5
#: rounds of removing views far above the rest, each followed by a fresh solve
REJECTION_ROUNDS = 3
TANGENTIAL_MODES = ("auto", "estimate", "zero")
#: "auto" keeps p1, p2 when holding them at zero raises the residual more than noise would
#: with this probability (the residual is not quite independent noise: views share small
#: biases, so the test is strict)
TANGENTIAL_P_VALUE = 1e-3
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12)


def tangential_mode(zero_tangent_dist: bool, tangent_dist: bool) -> str:
    """The tangential mode of camera_calibration-style flags: --zero-tangent-dist holds
    p1 = p2 = 0, --tangent-dist always estimates them, neither lets the views decide."""
    if zero_tangent_dist and tangent_dist:
        raise ProcessorError("--zero-tangent-dist and --tangent-dist contradict each other")
    return "zero" if zero_tangent_dist else "estimate" if tangent_dist else "auto"


@dataclass(frozen=True)
class CalibrationOptions:
    """Solver options, with camera_calibration's meaning (see the module docstring)."""
    fix_principal_point: bool = False
    fix_aspect_ratio: bool = False
    tangential: str = "auto"
    k_coefficients: int = 2

    def __post_init__(self) -> None:
        if not 0 <= self.k_coefficients <= 6:
            raise ProcessorError(f"--k-coefficients must be 0..6, got {self.k_coefficients}")
        if self.tangential not in TANGENTIAL_MODES:
            raise ProcessorError(f"tangential distortion must be one of "
                                 f"{', '.join(TANGENTIAL_MODES)}, got {self.tangential!r}")

    def with_tangential(self, mode: str) -> CalibrationOptions:
        """The same options with another tangential mode."""
        return dataclasses.replace(self, tangential=mode)

    @property
    def free_intrinsics(self) -> int:
        """How many intrinsic parameters the solver estimates."""
        focal = 1 if self.fix_aspect_ratio else 2
        centre = 0 if self.fix_principal_point else 2
        return focal + centre + self.k_coefficients + (0 if self.tangential == "zero" else 2)

    @property
    def distortion_model(self) -> str:
        """``rational_polynomial`` above 3 radial coefficients, else ``plumb_bob``."""
        return "rational_polynomial" if self.k_coefficients > 3 else "plumb_bob"

    @property
    def flags(self) -> int:
        """OpenCV's calibrateCamera flags for these options."""
        flags = 0
        if self.fix_principal_point:
            flags |= cv2.CALIB_FIX_PRINCIPAL_POINT
        if self.fix_aspect_ratio:
            flags |= cv2.CALIB_FIX_ASPECT_RATIO
        if self.tangential == "zero":
            flags |= cv2.CALIB_ZERO_TANGENT_DIST
        if self.k_coefficients > 3:
            flags |= cv2.CALIB_RATIONAL_MODEL
        for n, flag in enumerate((cv2.CALIB_FIX_K1, cv2.CALIB_FIX_K2, cv2.CALIB_FIX_K3,
                                  cv2.CALIB_FIX_K4, cv2.CALIB_FIX_K5, cv2.CALIB_FIX_K6), 1):
            if self.k_coefficients < n:
                flags |= flag
        return flags


@dataclass(frozen=True)
class TangentialTest:
    """Does the fit need p1, p2? ``chi2`` is the rise in the residual sum of squares when
    they are held at zero, in units of the free fit's residual variance; under "no
    tangential distortion" it follows a chi-square law with 2 degrees of freedom."""

    chi2: float
    estimated: bool  # the outcome: p1, p2 kept

    @property
    def p_value(self) -> float:
        """Probability of a rise this large without tangential distortion."""
        return math.exp(-max(self.chi2, 0.0) / 2.0)

    def describe(self) -> str:
        """The outcome in one sentence, with the statistic."""
        verdict = ("estimated" if self.estimated
                   else "held at zero (the views do not show any)")
        return (f"tangential distortion {verdict}: holding p1 = p2 = 0 raises the residual by "
                f"chi2(2) = {self.chi2:.1f}, p = {self.p_value:.2g} "
                f"(kept when p < {TANGENTIAL_P_VALUE:g})")


@dataclass
class MonoResult:
    """A calibrated camera and the evidence for it."""

    model: CameraModel
    rms_px: float
    view_ids: list[int]  # indices (into the views given) that were used
    view_rms_px: dict[int, float]  # per used view
    rejected: dict[int, str]  # view index -> why it was left out
    std: dict[str, float]  # standard deviation of every estimated parameter
    camera_from_board: dict[int, F64]  # (4, 4) per used view
    residuals_px: dict[int, F64] = field(default_factory=dict)  # (N, 2) per used view
    #: the options solved with: "auto" tangential distortion resolved to what was chosen
    options: CalibrationOptions = field(default_factory=CalibrationOptions)
    tangential_test: TangentialTest | None = None

    def parameters(self) -> dict[str, float]:
        """Estimated fx, fy, cx, cy and distortion coefficients by OpenCV name."""
        m = self.model
        names = ["fx", "fy", "cx", "cy", *_distortion_names(m.distortion_model)]
        values = [m.fx, m.fy, m.cx, m.cy, *m.d.tolist()]
        return dict(zip(names, values, strict=True))


def _distortion_names(model: str) -> list[str]:
    return (["k1", "k2", "p1", "p2", "k3"] if model == "plumb_bob"
            else ["k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"])


def _pose(rvec: np.ndarray, tvec: np.ndarray) -> F64:
    pose = np.eye(4)
    pose[:3, :3] = cv2.Rodrigues(rvec)[0]
    pose[:3, 3] = np.asarray(tvec).reshape(3)
    return pose


@dataclass(frozen=True)
class Solution:
    """One run of OpenCV's solver over some views (positions in the list it was given)."""

    rms_px: float
    model: CameraModel
    camera_from_board: list[F64]  # (4, 4) per view
    std: F64  # OpenCV's stdDeviationsIntrinsics, in STD_NAMES order
    view_rms_px: F64  # (V,) per view
    residuals_px: list[F64]  # (N, 2) per view: observed - projected


def solve_views(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                options: CalibrationOptions) -> Solution:
    """Calibrate once from every view given (no outlier rejection, no model choice)."""
    object_points = [points_in_board.astype(np.float32)] * len(corners)
    image_points = [c.reshape(-1, 1, 2).astype(np.float32) for c in corners]
    n_d = 8 if options.k_coefficients > 3 else 5
    k0 = np.eye(3)
    try:
        rms, k, d, rvecs, tvecs, std_in, _std_ex, per_view = cv2.calibrateCameraExtended(
            object_points, image_points, size, k0, np.zeros(n_d), flags=options.flags,
            criteria=CRITERIA,
        )
    except cv2.error as err:
        raise ProcessorError(f"calibration failed: {str(err).strip().splitlines()[-1]}") from None
    d = np.asarray(d, dtype=np.float64).reshape(-1)[:n_d]
    model = CameraModel(size[0], size[1], np.asarray(k, dtype=np.float64),
                        options.distortion_model, d)
    poses = [_pose(r, t) for r, t in zip(rvecs, tvecs, strict=True)]
    residuals = []
    for pose, c in zip(poses, corners, strict=True):
        projected = model.project(points_in_board @ pose[:3, :3].T + pose[:3, 3])
        residuals.append(c - projected)
    return Solution(float(rms), model, poses, np.asarray(std_in, dtype=np.float64).reshape(-1),
                    np.asarray(per_view, dtype=np.float64).reshape(-1), residuals)


def far_above_the_rest(view_ids: list[int], view_rms_px: F64, what: str) -> dict[int, str]:
    """Views whose RMS error exceeds max(OUTLIER_FACTOR x the median, OUTLIER_FLOOR_PX),
    with why; none when removing them would leave fewer than MIN_VIEWS."""
    median = float(np.median(view_rms_px))
    limit = max(OUTLIER_FACTOR * median, OUTLIER_FLOOR_PX)
    bad = {i: (f"{what} RMS {e:.3f} px > {limit:.3f} px "
               f"({OUTLIER_FACTOR:g}x the median {median:.3f} px)")
           for i, e in zip(view_ids, view_rms_px, strict=True) if e > limit}
    return bad if len(view_ids) - len(bad) >= MIN_VIEWS else {}


def calibrate_mono(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                   options: CalibrationOptions, *, reject_outliers: bool = True) -> MonoResult:
    """Calibrate from views ``corners[i]`` ``(N, 2)`` of the board points ``(N, 3)``.

    Views whose RMS error lies far above the rest are removed and the camera re-solved,
    up to three rounds. With ``tangential="auto"`` this is done with p1, p2 free; then the
    kept views are solved again with p1 = p2 = 0 and the better-supported model is returned.
    """
    if len(corners) < MIN_VIEWS:
        raise ProcessorError(
            f"too few good views to calibrate: {len(corners)} (need at least {MIN_VIEWS}); "
            "record more board poses"
        )
    solve_options = options.with_tangential("estimate") if options.tangential == "auto" \
        else options
    active = list(range(len(corners)))
    rejected: dict[int, str] = {}
    for round_ in range(REJECTION_ROUNDS + 1):
        solution = solve_views(points_in_board, [corners[i] for i in active], size,
                               solve_options)
        bad = far_above_the_rest(active, solution.view_rms_px, "reprojection") \
            if reject_outliers and round_ < REJECTION_ROUNDS else {}
        if not bad:
            break
        rejected |= bad
        active = [i for i in active if i not in rejected]
    test = None
    if options.tangential == "auto":
        zero_options = options.with_tangential("zero")
        without = solve_views(points_in_board, [corners[i] for i in active], size,
                              zero_options)
        observed = 2 * sum(len(corners[i]) for i in active)
        dof = observed - solve_options.free_intrinsics - 6 * len(active)
        chi2 = (without.rms_px ** 2 - solution.rms_px ** 2) / max(solution.rms_px ** 2, 1e-300) \
            * dof
        test = TangentialTest(chi2, estimated=False)
        test = dataclasses.replace(test, estimated=test.p_value < TANGENTIAL_P_VALUE)
        if not test.estimated:
            solution, solve_options = without, zero_options
    names = ["fx", "fy", "cx", "cy", *_distortion_names(solution.model.distortion_model)]
    sigma = {n: float(solution.std[STD_NAMES.index(n)]) for n in names}
    return MonoResult(
        model=solution.model, rms_px=solution.rms_px, view_ids=active,
        view_rms_px={i: float(e) for i, e in zip(active, solution.view_rms_px, strict=True)},
        rejected=rejected, std=sigma,
        camera_from_board=dict(zip(active, solution.camera_from_board, strict=True)),
        residuals_px=dict(zip(active, solution.residuals_px, strict=True)),
        options=solve_options, tangential_test=test,
    )


def max_projection_difference(a: CameraModel, b: CameraModel, step_px: int = 8,
                              within: F64 | None = None, *, align_rotation: bool = False) -> float:
    """Largest pixel distance between where ``a`` and ``b`` image the same ray.

    Over the whole image, or only inside the convex hull of the points ``within`` (N, 2),
    e.g. every corner the calibration saw: outside it a model only extrapolates.

    With ``align_rotation`` the rays of ``a`` are first turned by the rotation that best
    maps them onto ``b`` (least squares in pixels). Intrinsic calibration cannot observe a
    rotation of the camera frame: the board poses absorb it, and a principal point shift of
    δ px with tangential distortion is nearly such a rotation at a narrow field of view. The
    aligned difference is what two models disagree on once their frames agree, as mrcal's
    projection difference with an implied rotation.
    """
    us, vs = np.meshgrid(np.arange(0, a.width, step_px, dtype=np.float64),
                         np.arange(0, a.height, step_px, dtype=np.float64))
    pixels = np.column_stack([us.ravel(), vs.ravel()])
    if within is not None:
        hull = cv2.convexHull(np.asarray(within, dtype=np.float32).reshape(-1, 1, 2))
        inside = [cv2.pointPolygonTest(hull, (float(u), float(v)), False) >= 0
                  for u, v in pixels]
        pixels = pixels[np.asarray(inside, dtype=bool)]
    rays_in_a = np.column_stack([a.undistort_pixels(pixels), np.ones(len(pixels))])
    rvec_b_from_a = _best_rotation(rays_in_a, pixels, b) if align_rotation else np.zeros(3)
    uv, _ = cv2.projectPoints(rays_in_a, rvec_b_from_a, np.zeros(3), b.k, b.d)
    return float(np.linalg.norm(uv.reshape(-1, 2) - pixels, axis=1).max())


def _best_rotation(rays: F64, pixels: F64, model: CameraModel, iterations: int = 20) -> F64:
    """Rotation vector ``r`` minimising the pixel error of ``model`` imaging ``R(r) rays``
    at ``pixels`` (Gauss-Newton; the rotation is small, so it starts from zero)."""
    rvec = np.zeros(3)
    for _ in range(iterations):
        uv, jacobian = cv2.projectPoints(rays, rvec, np.zeros(3), model.k, model.d)
        error = (uv.reshape(-1, 2) - pixels).reshape(-1)
        step = np.linalg.lstsq(jacobian[:, :3], -error, rcond=None)[0]
        rvec = rvec + step
        if np.abs(step).max() < 1e-12:
            break
    return rvec


def cross_validate(points_in_board: F64, corners: list[F64], size: tuple[int, int],
                   options: CalibrationOptions, seed: int = 0) -> float | None:
    """Calibrate two disjoint halves separately; their max projection difference (px) over
    the image, after aligning their camera frames (see :func:`max_projection_difference`)."""
    if len(corners) < 2 * MIN_VIEWS:
        return None
    order = np.random.default_rng(seed).permutation(len(corners))
    halves = [order[: len(order) // 2], order[len(order) // 2:]]
    models = [
        calibrate_mono(points_in_board, [corners[i] for i in h], size, options,
                       reject_outliers=False).model
        for h in halves
    ]
    return max_projection_difference(models[0], models[1], align_rotation=True)
