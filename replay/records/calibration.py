"""The records ``camlog calibrate`` writes: per-view residuals and the calibration summary.

``{ns}/calibration/residuals`` holds one :class:`ViewResiduals` per used view;
``/calibration/summary`` (and ``calibration.json``) one :class:`CalibrationSummary`. Every
length is in pixels (``_px``) or metres (``_m``), every stamp in nanoseconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import RecordError
from ..messages import F64
from .base import OMIT_NONE, JsonRecord, from_json, to_json
from .rig import RigSummary
from .time_offset import TimeOffset

__all__ = [
    "BoardSummary",
    "BoardWarpSummary",
    "CalibrationSummary",
    "CameraSummary",
    "CoverageSummary",
    "EvidenceSummary",
    "LensOrderSummary",
    "LogCalibration",
    "LogStereoCalibration",
    "OptionsSummary",
    "ParameterEstimate",
    "RangeProgress",
    "RejectedJointView",
    "RejectedView",
    "StereoSummary",
    "StereoTruth",
    "TangentialSummary",
    "TimeOffsetSummary",
    "UncertaintySummary",
    "ViewResiduals",
]


@dataclass(frozen=True)
class ViewResiduals(JsonRecord):
    """One used calibration view: detected ``corners_px`` (N, 2) and ``residuals_px`` (N, 2),
    observed minus reprojected, the view's RMS over its inlier corners and the indices of
    the corners left out as outliers. A held pose's view is stamped at its first frame;
    ``until_ns`` is the stamp of the last frame it covers (None: that frame alone).
    ``corners_in_camera_m`` (N, 3): where the solution puts the board points of the corners,
    in the camera's optical frame (the calibrated model images them at ``corners_px -
    residuals_px``)."""

    what = "residuals record"

    stamp_ns: int
    frame_id: str
    rms_px: float
    corners_px: F64
    residuals_px: F64
    outliers: list[int] = field(default_factory=list)
    until_ns: int | None = None
    corners_in_camera_m: F64 | None = field(default=None, metadata=OMIT_NONE)

    def __post_init__(self) -> None:
        corners = np.asarray(self.corners_px, dtype=np.float64).reshape(-1, 2)
        residuals = np.asarray(self.residuals_px, dtype=np.float64).reshape(-1, 2)
        if corners.shape != residuals.shape:
            raise RecordError(f"{len(corners)} corners but {len(residuals)} residuals")
        object.__setattr__(self, "corners_px", corners)
        object.__setattr__(self, "residuals_px", residuals)
        if self.corners_in_camera_m is not None:
            points = np.asarray(self.corners_in_camera_m, dtype=np.float64)
            if points.shape != (len(corners), 3):
                raise RecordError(f"{len(corners)} corners but {len(points)} board points")
            object.__setattr__(self, "corners_in_camera_m", points)


@dataclass(frozen=True)
class BoardSummary:
    """The calibration target: ``cols`` x ``rows`` inner corners, ``square_m`` squares; a
    circle grid's circles ``diameter_m`` across, measured in the images or given."""

    pattern: str
    cols: int
    rows: int
    square_m: float
    diameter_m: float | None = field(default=None, metadata=OMIT_NONE)
    diameter_measured: bool | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class BoardWarpSummary:
    """The board's warp (``mode`` auto, on): whether it was ``estimated``, the bow of the
    board's middle out of the plane of its edges along its x and y ``warp_mm`` with
    standard deviations ``warp_std_mm``; with ``auto`` the cross-validation over the views
    that decided: held-out RMS reprojection error flat and warped (px), the relative
    ``gain``, the signed-rank ``p_value``; the choice in words."""

    mode: str
    estimated: bool
    summary: str
    warp_mm: list[float] | None = field(default=None, metadata=OMIT_NONE)
    warp_std_mm: list[float] | None = field(default=None, metadata=OMIT_NONE)
    held_out_rms_px: list[float] | None = field(default=None, metadata=OMIT_NONE)
    gain: float | None = field(default=None, metadata=OMIT_NONE)
    p_value: float | None = field(default=None, metadata=OMIT_NONE)
    views: int | None = field(default=None, metadata=OMIT_NONE)
    folds: int | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class OptionsSummary:
    """The solver options (camera_calibration's meaning); with ``choose_order`` the model
    and radial count are where the choice of each camera's radial order starts (its
    ``lens_order`` says what was chosen)."""

    fix_principal_point: bool
    fix_aspect_ratio: bool
    tangential: str
    k_coefficients: int
    distortion_model: str
    choose_order: bool | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class RejectedView:
    """A frame left out of the calibration, and why."""

    stamp_ns: int
    reason: str


@dataclass(frozen=True)
class ParameterEstimate:
    """One estimated parameter with its standard deviation (0: held fixed) and, when the
    log has the simulator's truth, the true value and the error (estimate - truth)."""

    value: float
    std: float
    truth: float | None = field(default=None, metadata=OMIT_NONE)
    error: float | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class TangentialSummary:
    """Whether p1, p2 were estimated, and the likelihood-ratio test that decided it."""

    estimated: bool
    chi2: float | None = field(default=None, metadata=OMIT_NONE)
    p_value: float | None = field(default=None, metadata=OMIT_NONE)
    summary: str | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class LensOrderSummary:
    """The radial order chosen by cross-validation over the views: every candidate tried
    (``plumb_bob k1 k2``, ...) with its held-out RMS reprojection error (px; none when too
    few views left no choice), the one chosen and the choice in words."""

    candidates: list[str]
    held_out_rms_px: list[float]
    chosen: str
    views: int
    folds: int
    summary: str


@dataclass(frozen=True)
class RangeProgress:
    """How much of one view parameter's range (X, Y, size, skew) the used views cover."""

    min: float
    max: float
    progress: float


@dataclass(frozen=True)
class CoverageSummary:
    """Coverage per view parameter, and the share of image cells that saw a corner.

    JSON: ``{"X": {...}, "Y": {...}, ..., "image_cells": 0.8}``."""

    ranges: dict[str, RangeProgress]
    image_cells: float

    def json_value(self) -> dict[str, Any]:
        """The JSON object (ranges by name, then ``image_cells``)."""
        return {**to_json(self.ranges), "image_cells": self.image_cells}

    @classmethod
    def from_json_value(cls, data: Any, where: str) -> CoverageSummary:
        """Parse the JSON object :meth:`json_value` writes."""
        if not isinstance(data, dict) or "image_cells" not in data:
            raise RecordError(f"{where}: expected an object with image_cells")
        ranges = {k: from_json(RangeProgress, v, f"{where}.{k}")
                  for k, v in data.items() if k != "image_cells"}
        cells = data["image_cells"]
        if isinstance(cells, bool) or not isinstance(cells, int | float):
            raise RecordError(f"{where}.image_cells: expected a number")
        return cls(ranges, float(cells))


@dataclass(frozen=True)
class EvidenceSummary:
    """What the frames gave: how many went into the used views (a held pose averages its
    frames into one view), views left out as outliers or as too blurred, outlier corners,
    the corner noise the residuals show, the frame-to-frame scatter of held corners, the
    motion-blur law (None when the views show no blur) and what measuring the corners again
    did (None when they were not: a fisheye's chessboard and ChArUco corners are)."""

    frames_used: int
    views: int
    held_views: int
    outlier_views: int
    blurred_views: int
    outlier_corners: int
    corner_noise_px: float
    frame_scatter_px: float | None = field(default=None, metadata=OMIT_NONE)
    blur: str | None = field(default=None, metadata=OMIT_NONE)
    measured_again: str | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class UncertaintySummary:
    """Projection uncertainty over the image (1 sigma, worst direction) at ``range_m`` and
    for rays (points far away), the calibration's error expected from cross-validation
    (half the difference of two halves of the evidence, rays, measured as the uncertainty) and, in
    simulated logs, the true error; median and worst over the image, px.

    ``true_error_*`` and ``rays_true_error_*`` measure what the uncertainty predicts (mrcal's
    mean frames): the point the estimate puts at a pixel is carried into every board frame
    by the estimated poses and back by the true ones, then imaged by the true camera.
    ``aligned_true_error_*`` compares only the lenses, for rays, after the rotation that best
    aligns the camera frames (as the max projection difference does).
    """

    range_m: float
    median_px: float
    worst_px: float
    rays_median_px: float  # the same for points far away (rays): comparable to the rest
    rays_worst_px: float
    cross_validation_median_px: float | None = field(default=None, metadata=OMIT_NONE)
    cross_validation_worst_px: float | None = field(default=None, metadata=OMIT_NONE)
    true_error_median_px: float | None = field(default=None, metadata=OMIT_NONE)
    true_error_worst_px: float | None = field(default=None, metadata=OMIT_NONE)
    rays_true_error_median_px: float | None = field(default=None, metadata=OMIT_NONE)
    rays_true_error_worst_px: float | None = field(default=None, metadata=OMIT_NONE)
    aligned_true_error_median_px: float | None = field(default=None, metadata=OMIT_NONE)
    aligned_true_error_worst_px: float | None = field(default=None, metadata=OMIT_NONE)
    #: the largest projection difference (px) from the model fitted with the terms the
    #: calibration left out (p1 p2 its tangential test dropped, k3 beside the k1 k2 the views
    #: chose), included in the figures above
    left_out_worst_px: float | None = field(default=None, metadata=OMIT_NONE)
    #: where no board reached (extrapolated): the largest uncertainty there (1 sigma, px, the
    #: worse of the working range and rays), the share of the image grid and its parts
    beyond_boards_px: float | None = field(default=None, metadata=OMIT_NONE)
    beyond_boards_share: float | None = field(default=None, metadata=OMIT_NONE)
    beyond_boards_where: str | None = field(default=None, metadata=OMIT_NONE)

    @property
    def beyond_boards_line(self) -> str | None:
        """``beyond the boards (corners of the image, 12 % of the image): ±0.020 px (1 sigma)
        — hold the board there to pin it`` (None: the boards reached the whole image)."""
        if self.beyond_boards_px is None or self.beyond_boards_share is None:
            return None
        return (f"beyond the boards ({self.beyond_boards_where}, "
                f"{100 * self.beyond_boards_share:.0f} % of the image): "
                f"±{self.beyond_boards_px:.3f} px (1 sigma) — hold the board there to pin it")


@dataclass(frozen=True)
class TimeOffsetSummary:
    """How much later a camera stamps an instant than the rig's first camera
    (``reference``), measured from the board's motion: in words (``summary``), the estimate
    (``measured``; None when the log does not show it: a held board, snapshots), whether
    the views were paired by it (``applied``) and, in a simulated log, the true offset (the
    difference of the cameras' latencies) and the estimate's error (ms)."""

    reference: str
    summary: str
    applied: bool
    measured: TimeOffset | None = field(default=None, metadata=OMIT_NONE)
    truth_ms: float | None = field(default=None, metadata=OMIT_NONE)
    error_ms: float | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class LogCalibration:
    """The calibration the log carries (its camera_info: an imported camera_calibration
    archive's result, a driver's factory values) beside camlog's, on the views camlog used:
    its ``fx`` ... ``cy`` (px); the reprojection RMS of its model and of camlog's on those
    views' corners (those camlog kept), each view's board pose fitted to the model (px); and
    the largest distance between where the two models image one ray once a rotation aligns
    their camera frames, over the whole image and where the views put corners (px)."""

    info_topic: str
    distortion_model: str
    fx: float
    fy: float
    cx: float
    cy: float
    rms_px: float
    camlog_rms_px: float
    max_projection_difference_px: float
    max_projection_difference_covered_px: float


@dataclass(frozen=True)
class LogStereoCalibration:
    """The rig the log's two camera_infos imply (their rectifications and the right
    camera's projection) beside camlog's: its baseline (m), camlog's baseline minus it (%
    of it), and the angle between the two rotations ``right_from_left`` (degrees)."""

    baseline_m: float
    baseline_difference_percent: float
    rotation_difference_deg: float


@dataclass(frozen=True)
class CameraSummary:
    """One calibrated camera: what its frames gave, the model, its evidence and accuracy.

    The ``max_projection_difference_vs_truth*`` figures exist when the log has the
    simulator's truth: over the whole image or only where the views put corners
    (``_covered``), with or without aligning the camera frames by a rotation (``_aligned``).
    """

    namespace: str
    image_topic: str
    width: int
    height: int
    frames: int
    distinct_frames: int
    boards_found: int
    candidate_views: int
    selected_views: int
    used_views: int
    rejected: list[RejectedView]
    rms_px: float
    distortion_model: str
    parameters: dict[str, ParameterEstimate]
    cross_validation_px: float | None
    tangential: TangentialSummary
    coverage: CoverageSummary
    max_projection_difference_vs_truth_px: float | None = field(default=None,
                                                                metadata=OMIT_NONE)
    max_projection_difference_vs_truth_aligned_px: float | None = field(default=None,
                                                                        metadata=OMIT_NONE)
    max_projection_difference_vs_truth_covered_px: float | None = field(default=None,
                                                                        metadata=OMIT_NONE)
    max_projection_difference_vs_truth_covered_aligned_px: float | None = field(
        default=None, metadata=OMIT_NONE)
    evidence: EvidenceSummary | None = field(default=None, metadata=OMIT_NONE)
    uncertainty: UncertaintySummary | None = field(default=None, metadata=OMIT_NONE)
    lens_order: LensOrderSummary | None = field(default=None, metadata=OMIT_NONE)
    time_offset: TimeOffsetSummary | None = field(default=None, metadata=OMIT_NONE)
    log_calibration: LogCalibration | None = field(default=None, metadata=OMIT_NONE)

    @property
    def has_truth(self) -> bool:
        """Whether the parameters were compared with the simulator's truth."""
        return any(p.truth is not None for p in self.parameters.values())


@dataclass(frozen=True)
class RejectedJointView:
    """A stereo pair left out of the stereo solve, and why."""

    left_stamp_ns: int
    right_stamp_ns: int
    reason: str


@dataclass(frozen=True)
class StereoTruth:
    """The simulator's true baseline and the estimate's relative error."""

    baseline_m: float
    baseline_error_percent: float


@dataclass(frozen=True)
class StereoSummary:
    """The stereo solve: RMS, epipolar error after rectification, the rig transform
    (``translation_m`` (3,) of ``right_from_left``), and the board square re-estimated by
    triangulation."""

    rms_px: float
    epipolar_rms_px: float
    baseline_m: float
    baseline_std_m: float
    square_m: float
    rotation_deg: float
    translation_m: list[float]
    joint_views: int
    rejected: list[RejectedJointView]
    truth: StereoTruth | None = field(default=None, metadata=OMIT_NONE)
    rotation_std_deg: float | None = field(default=None, metadata=OMIT_NONE)
    log_calibration: LogStereoCalibration | None = field(default=None, metadata=OMIT_NONE)


@dataclass(frozen=True)
class CalibrationSummary(JsonRecord):
    """Machine-readable results of ``camlog calibrate`` (``/calibration/summary`` and
    ``calibration.json``)."""

    what = "calibration summary"

    board: BoardSummary
    options: OptionsSummary
    cameras: list[CameraSummary]
    ground_truth: bool
    stereo: StereoSummary | None = field(default=None, metadata=OMIT_NONE)
    rig: RigSummary | None = field(default=None, metadata=OMIT_NONE)
    board_warp: BoardWarpSummary | None = field(default=None, metadata=OMIT_NONE)

    def rejected_stamps(self) -> dict[str, dict[int, str]]:
        """Camera namespace -> stamp of every rejected frame -> why."""
        return {c.namespace: {r.stamp_ns: r.reason for r in c.rejected} for c in self.cameras}
