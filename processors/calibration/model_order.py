"""The radial order of the lens model, chosen by cross-validation over whole views.

The candidates form a ladder (:func:`order_candidates`): plumb_bob's k1 k2, then k1 k2 k3,
then (when no model was named) rational_polynomial's k1..k6. The views are cut into
:data:`ORDER_FOLDS` contiguous blocks (views in time order: a moving board's neighbouring
views, nearly one pose, are held out together). For each block and candidate, OpenCV's
calibration of the other views gives the intrinsics; each held-out view's board pose alone is
then solved with them (PnP) and its mean squared reprojection error ``e(v)`` (px²) measured.
Every view is held out once, so every candidate has one held-out error per view. Held-out
views lie where the training views lie: when they choose k1 k2, k1 k2 k3 is also compared with
them beyond the views (:func:`~.beyond.k3_beyond_the_views`, :data:`BEYOND_RATIO`).

The ladder is climbed while each rung is taken (a bigger order is tried only when the one
below it was needed): each rung is compared with the one below by the paired differences
``d(v) = e_small(v) - e_big(v)`` over the held-out views. Views are the units: an error the
corners of a view share (a moving board's blur, a pose the view's corners pull together)
enters ``d`` once per view, not once per corner, so it cannot make a bigger model look
needed as it did a likelihood ratio over corners; and a held-out view's error includes
every error of the model where that view lies, so a coefficient that only fits the training
views' noise raises it. The bigger model is chosen when both

* its held-out error is lower by at least :data:`MIN_GAIN` (``1 - sum e_big / sum e_small``):
  a gain too small to matter is not worth the extra coefficient's extrapolation, and
* the paired differences lean to the bigger model: Wilcoxon's signed-rank test
  (:func:`signed_rank_p`, one-sided) gives p < :data:`MAX_P_VALUE` under "neither is
  better". Ranks, not a t statistic: a lens term shows where the boards reach far from
  the centre, so true gains are few and large among many differences near zero, and a t
  statistic's spread, made by those same large gains, hides them; one odd view, however
  large its difference, counts as one rank. The exact law keeps the test honest with few
  views (a normal approximation's z = 3 is out of reach below 12 views); past
  :data:`EXACT_RANKS` views its normal approximation is as good, and finite however many.

Views far off under the smallest order (:data:`FAR_VIEW_FACTOR` times the median view's
error: not the board, or blurred) are left out of the comparison, and each fold's fit sees
an even sample of at most :data:`FOLD_VIEWS` training views (the cost stays that of a few
seed calibrations however long the log). Every view is held out and measured, however many:
on a 40 s waved board (1 036 views) an even sample of 218 chose k1 k2 where every view chose
k1 k2 k3, whose max projection difference from the truth was lower (0.029 against 0.041 px).
The folds are fitted on threads (OpenCV's solver releases the GIL; each fit alone on one
thread, see :func:`~.seed.one_opencv_thread`), and the cameras climb their ladders at the same
time: the same fits, in less time on several cores.
The folds' models share most of their views, so the views' differences are not quite
independent; the thresholds are strict for that reason. OpenCV's solver fits the
folds (rational_polynomial without the joint solve's light prior on k4..k6): the choice
compares orders, and the joint solve then fits the chosen one from every view.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from replay.camera import CameraModel
from replay.messages import F64

from ..errors import ProcessorError
from .opencv_lens import opencv_lens
from .options import CalibrationOptions
from .robust import BoardView, camera_views
from .seed import board_pose, opencv_calibration, spread

__all__ = ["BEYOND_RATIO", "EXACT_RANKS", "MAX_P_VALUE", "MIN_GAIN", "ORDER_FOLDS", "OrderChoice",
           "OrderStep", "choose_order", "choose_orders", "order_candidates", "order_label",
           "signed_rank_p"]

ORDER_FOLDS = 5
#: k1 k2 chosen by the views give way to k1 k2 k3 when, somewhere in the image, the two
#: models' projections part by more than this many times k1 k2's own uncertainty: k1 k2 then
#: do not hold their own figure beyond the views (see :func:`~.beyond.k3_beyond_the_views`).
#: Measured: 0.3-2.5 on a waved board through a k3 lens (7 seeds, 10 s), 1.76 at 40 s; at
#: most 0.31 where the lens has no k3 that matters (mono_heldout, mono_moving_blur, 13 seeds)
BEYOND_RATIO = 1.0
#: the bigger model lowers the held-out error by at least this share ...
MIN_GAIN = 0.01
#: ... and the views' paired differences favour it with a signed-rank p below this (on the
#: benchmarks' seeds whose lenses show no k3, the k3 rung's p stayed above 0.07)
MAX_P_VALUE = 0.01
#: views OpenCV's solver sees in each fold (an even sample of the training views)
FOLD_VIEWS = 30
#: a view takes part with at least this many corners (its pose has 6 unknowns)
MIN_CORNERS = 6
#: a view whose held-out error under the smallest order is this many times the median view's
#: is not measured (not the board, or blurred: its error is not the lens's)
FAR_VIEW_FACTOR = 10.0
#: fewer views than this: no choice, the smallest order is kept
MIN_ORDER_VIEWS = 2 * ORDER_FOLDS
#: up to this many paired differences the signed-rank law is exact (a few million additions);
#: beyond, its normal approximation is within 1e-4 of it
EXACT_RANKS = 200

#: how the folds of one rung are fitted: a ``map`` that keeps their order (the builtin, or a
#: thread pool's)
FoldMap = Callable[[Callable[[np.ndarray], F64 | None], Iterable[np.ndarray]],
                   Iterator[F64 | None]]


def order_candidates(options: CalibrationOptions) -> list[CalibrationOptions]:
    """The ladder of orders to choose from, smallest first: plumb_bob k1 k2 and k1 k2 k3,
    then rational_polynomial k1..k6 unless ``options`` name plumb_bob; a model without
    that ladder (equidistant, rational_polynomial named) is its options alone."""
    model = options.model
    if model not in (None, "plumb_bob"):
        return [dataclasses.replace(options, choose_order=False)]
    ladder = [dataclasses.replace(options, k_coefficients=k, model="plumb_bob",
                                  choose_order=False) for k in (2, 3)]
    if model is None:
        ladder.append(dataclasses.replace(options, k_coefficients=6,
                                          model="rational_polynomial", choose_order=False))
    return ladder


def order_label(options: CalibrationOptions) -> str:
    """``plumb_bob k1 k2``, ``rational_polynomial k1..k6``, ..."""
    count = options.radial_count
    radial = " ".join(f"k{i}" for i in range(1, count + 1)) if count <= 3 else f"k1..k{count}"
    return f"{options.distortion_model} {radial or 'no radial terms'}"


@dataclass(frozen=True)
class OrderStep:
    """One rung of the ladder against the order chosen before it: the relative fall of the
    held-out error ``gain`` and the one-sided signed-rank ``p_value`` of the views' paired
    differences."""

    smaller: int  # candidate index
    bigger: int
    gain: float
    p_value: float

    @property
    def taken(self) -> bool:
        """Whether the bigger order is chosen (:data:`MIN_GAIN` and :data:`MAX_P_VALUE`
        met)."""
        return self.gain >= MIN_GAIN and self.p_value < MAX_P_VALUE


@dataclass(frozen=True)
class OrderChoice:
    """The candidates tried (the ladder up to the first rung not taken), each one's held-out
    error per view ``(V,)`` (px²; inf where not measured: its fold's fit failed, or the
    view is far off under the smallest order, see :data:`FAR_VIEW_FACTOR`), the rungs
    compared and the order chosen; without a choice (``why_not``), the smallest candidate
    alone and no errors."""

    candidates: list[CalibrationOptions]
    held_out_px2: list[F64]
    steps: list[OrderStep]
    chosen: int
    folds: int
    why_not: str | None = None  # why no choice was made (too few views)
    #: k1 k2 against k1 k2 k3 fitted to every view, when the views chose k1 k2: the largest
    #: ratio over the image of their projection difference to k1 k2's uncertainty, and the
    #: largest difference (px); k3 is kept above :data:`BEYOND_RATIO` (see
    #: :func:`~.beyond.k3_beyond_the_views`)
    beyond_ratio: float | None = None
    beyond_px: float | None = None

    @property
    def options(self) -> CalibrationOptions:
        """The chosen candidate's options."""
        return self.candidates[self.chosen]

    @property
    def held_out_rms_px(self) -> list[float]:
        """Each candidate's RMS held-out error over the views it measured (px)."""
        return [math.sqrt(float(np.mean(e[np.isfinite(e)]))) if np.isfinite(e).any()
                else math.nan for e in self.held_out_px2]

    @property
    def views(self) -> int:
        """How many views the smallest order's held-out error measured (0 without a
        choice)."""
        return int(np.isfinite(self.held_out_px2[0]).sum()) if self.held_out_px2 else 0

    def describe(self) -> str:
        """The choice and its evidence in one line."""
        chosen = order_label(self.options)
        if self.why_not is not None:
            return f"lens model {chosen}: not cross-validated ({self.why_not})"
        errors = ", ".join(f"{order_label(c)} {e:.4f}" for c, e in
                           zip(self.candidates, self.held_out_rms_px, strict=True))
        steps = "; ".join(
            f"{order_label(self.candidates[s.bigger]).split(' ', 1)[1]} "
            f"{'taken' if s.taken else 'not taken'}: gain {100 * s.gain:+.1f} %, "
            f"p = {s.p_value:.2g}" for s in self.steps)
        # k3 kept beyond the views: the views themselves chose k1 k2
        beyond = self.beyond_ratio is not None and self.options.radial_count == 3
        text = (f"lens model {chosen}{':' if beyond else ' chosen by'} cross-validation over "
                f"{self.folds} folds of {self.views} views: held-out RMS {errors} px; {steps} "
                f"(a bigger order needs a gain ≥ {100 * MIN_GAIN:g} % and p < {MAX_P_VALUE:g})")
        if self.beyond_ratio is not None and self.beyond_px is not None:
            kept = "k3 kept" if beyond else "k1 k2 kept"
            text += (f"; beyond the views k1 k2 and k1 k2 k3 part by up to {self.beyond_px:.3f} "
                     f"px, {self.beyond_ratio:.2f} times k1 k2's uncertainty: {kept} (k3 is "
                     f"kept above {BEYOND_RATIO:g} times)")
        return text


def choose_order(points_in_board: F64, views: list[tuple[npt.NDArray[np.int64], F64]],
                 size: tuple[int, int], candidates: list[CalibrationOptions], *,
                 folds: int = ORDER_FOLDS, fold_map: FoldMap = map) -> OrderChoice:
    """Choose among ``candidates`` (smallest first, see :func:`order_candidates`) from one
    camera's ``views`` in time order: each ``(point_ids (M,), corners_px (M, 2))`` of the
    board points ``points_in_board`` ``(N, 3)`` (see the module docstring); ``fold_map``
    fits a rung's folds (e.g. a thread pool's ``map``)."""
    usable = [(points_in_board[ids], np.asarray(c, dtype=np.float64)) for ids, c in views
              if len(ids) >= MIN_CORNERS]
    if len(candidates) == 1 or len(usable) < MIN_ORDER_VIEWS:
        why = "no other order to choose" if len(candidates) == 1 else \
            f"{len(usable)} views, fewer than {MIN_ORDER_VIEWS}"
        return OrderChoice(candidates[:1], [], [], 0, 0, why)
    blocks = np.array_split(np.arange(len(usable)), folds)
    smallest = _held_out_px2(usable, blocks, size, candidates[0], fold_map)
    far = _far_views(smallest)
    held_out = [np.where(far, math.inf, smallest)]
    steps: list[OrderStep] = []
    while len(held_out) < len(candidates) and all(s.taken for s in steps):
        bigger = _held_out_px2(usable, blocks, size, candidates[len(held_out)], fold_map)
        held_out.append(np.where(far, math.inf, bigger))
        steps.append(_compare(held_out[-2], held_out[-1], len(held_out) - 2,
                              len(held_out) - 1))
    return OrderChoice(candidates[:len(held_out)], held_out, steps,
                       sum(s.taken for s in steps), folds)


def _far_views(smallest_px2: F64) -> npt.NDArray[np.bool_]:
    """The views far off under the smallest order (:data:`FAR_VIEW_FACTOR`)."""
    measured = smallest_px2[np.isfinite(smallest_px2)]
    if not len(measured):
        return np.zeros(len(smallest_px2), dtype=bool)
    return ~(smallest_px2 <= FAR_VIEW_FACTOR * float(np.median(measured)))


def choose_orders(points_in_board: F64, views: list[BoardView], sizes: list[tuple[int, int]],
                  options: CalibrationOptions) -> list[OrderChoice | None]:
    """Each camera's choice (:func:`choose_order` on its views) when ``options`` ask for
    one (``choose_order``), else None for every camera. The cameras climb at once, and the
    folds are fitted on as many threads as there are cores."""
    if not options.choose_order:
        return [None] * len(sizes)
    candidates = order_candidates(options)
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1,
                            thread_name_prefix="camlog-folds") as folds, \
            ThreadPoolExecutor(max_workers=len(sizes),
                               thread_name_prefix="camlog-order") as cameras:
        chosen = [cameras.submit(choose_order, points_in_board,
                                 [(views[i].point_ids, views[i].corners_px)
                                  for i in camera_views(views, camera)], size, candidates,
                                 fold_map=folds.map)
                  for camera, size in enumerate(sizes)]
        return [future.result() for future in chosen]


def _compare(small: F64, big: F64, smaller: int, bigger: int) -> OrderStep:
    """The paired comparison of two candidates' held-out errors, over the views both
    measured (none taken with fewer than :data:`MIN_ORDER_VIEWS`)."""
    both = np.isfinite(small) & np.isfinite(big)
    if both.sum() < MIN_ORDER_VIEWS:
        return OrderStep(smaller, bigger, -math.inf, -math.inf)
    difference = small[both] - big[both]
    gain = float(1.0 - big[both].sum() / small[both].sum())
    return OrderStep(smaller, bigger, gain, signed_rank_p(difference))


def signed_rank_p(difference: F64) -> float:
    """One-sided p-value of Wilcoxon's signed-rank test that paired differences ``(V,)``
    lean positive: the probability, were each difference's sign a fair coin, of a sum of
    positive ranks this large or larger (zeros left out, tied sizes share their mean rank).

    Up to :data:`EXACT_RANKS` differences the law of that sum is summed exactly, as
    probabilities (each rank halves them: no count of ``2**V`` subsets overflows); beyond, it
    is the normal law of the same mean and variance (the ties' share taken out), with a
    continuity correction of half a rank, as :func:`scipy.stats.wilcoxon`'s approximation.
    """
    nonzero = difference[difference != 0]
    count = len(nonzero)
    if not count:
        return 1.0
    _values, group, size = np.unique(np.abs(nonzero), return_inverse=True,
                                     return_counts=True)
    first = np.cumsum(size) - size  # rank - 1 of each group's first member
    doubled = (2 * first + size + 1)[group]  # twice the mean ranks: integers >= 2
    observed = int(doubled[nonzero > 0].sum())
    if count <= EXACT_RANKS:
        law = np.zeros(int(doubled.sum()) + 1)
        law[0] = 1.0
        for rank in doubled.tolist():  # the law of the sum of a random subset of the ranks
            law[rank:] = law[rank:] + law[:-rank]
            law *= 0.5
        return float(min(1.0, law[observed:].sum()))
    mean = count * (count + 1) / 4
    ties = size.astype(np.float64)
    variance = count * (count + 1) * (2 * count + 1) / 24 - float(np.sum(ties ** 3 - ties)) / 48
    z = (observed / 2 - mean - 0.5) / math.sqrt(variance)
    return 0.5 * math.erfc(z / math.sqrt(2))


def _held_out_px2(views: list[tuple[F64, F64]], blocks: list[np.ndarray],
                  size: tuple[int, int], options: CalibrationOptions,
                  fold_map: FoldMap = map) -> F64:
    """Every view's mean squared error (px²) under the model fitted without its block (inf
    for a block whose fit fails); ``fold_map`` fits the blocks."""
    errors = np.full(len(views), math.inf)
    fitted = fold_map(lambda block: _fold_px2(views, block, size, options), blocks)
    for block, block_px2 in zip(blocks, fitted, strict=True):
        if block_px2 is not None:
            errors[block] = block_px2
    return errors


def _fold_px2(views: list[tuple[F64, F64]], block: np.ndarray, size: tuple[int, int],
              options: CalibrationOptions) -> F64 | None:
    """The held-out errors (px²) of ``block``'s views under the model fitted without them
    (None when that fit fails)."""
    held = set(block.tolist())
    training = [v for i, v in enumerate(views) if i not in held]
    pick = spread(len(training), FOLD_VIEWS)
    try:
        model = opencv_calibration([training[i][0] for i in pick],
                                   [training[i][1] for i in pick], size, options)
    except ProcessorError:
        return None
    return np.array([_view_px2(views[i][0], views[i][1], model) for i in block],
                    dtype=np.float64)


def _view_px2(points: F64, corners_px: F64, model: CameraModel) -> float:
    """Mean squared reprojection error (px²) of one view, its pose alone fitted to it."""
    pose = board_pose(points, corners_px, model)
    if pose is None:
        return math.inf
    pose = opencv_lens(model.distortion_model).refine_pose(points, corners_px, model, pose)
    projected = model.project(points @ pose[:3, :3].T + pose[:3, 3])
    return float(np.mean(np.sum((projected - corners_px) ** 2, axis=1)))
