"""Detection scores on one scale: calibration, and suppression of duplicate boxes.

Detectors report confidence on scales of their own: probabilities in [0, 1] (most CNN
detectors), or raw margins such as the DPM's, about −1 … 140 in the MOTChallenge 2015 public
detections. The tracker's score thresholds (``TrackerConfig.score_high``, ``min_score``) are
read on a *calibrated* scale ``c ∈ [0, 1]`` given by ``TrackerConfig.score_scale``:

``"auto"`` (default)
    the empirical distribution function of the scores seen so far,

    .. math:: c(s) = \\frac{\\#\\{s_j \\le s\\}}{n},

    over the ``n`` scores of the run up to and including the current frame (online and, by
    default, offline), or over given scores (:meth:`ScoreCalibration.prime`). ``c`` depends
    only on the order of the scores, so any strictly increasing rescaling of a detector's
    scores gives the same tracks, and a threshold ``score_high = 0.3`` means "above the
    lowest 30 % of this detector's boxes". A run
    whose scores are all equal (detections without a score, blobs) has ``c = 1`` everywhere.
    Memory is bounded: past ``capacity`` scores the sorted sample keeps every second one.
``"prob"``
    the scores are probabilities already: ``c = clip(s, 0, 1)``.
``(lo, hi)``
    a fixed linear scale: ``c = clip((s − lo) / (hi − lo), 0, 1)``.

:func:`duplicates` finds, within one frame, the boxes that overlap a higher-scored box by an
IoU of at least a threshold (greedy non-maximum suppression); :func:`isolated`, the boxes that
overlap none of some others (``TrackerConfig.low_birth_iou``: the low boxes that may start a
tentative track).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.association.gating import spatial_pairs

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: The named calibrations (besides a ``(lo, hi)`` pair).
SCALES = ("auto", "prob")


def check_scale(scale: Any) -> str | tuple[float, float]:
    """``scale`` validated: ``"auto"``, ``"prob"`` or a pair ``(lo, hi)`` with ``lo < hi``.

    Raises
    ------
    ValueError
        Anything else, in one line.
    """
    if isinstance(scale, str):
        if scale in SCALES:
            return scale
        raise ValueError(
            f"score scale must be one of {', '.join(SCALES)} or a pair LO,HI (got {scale!r})"
        )
    try:
        lo, hi = (float(v) for v in scale)
    except (TypeError, ValueError):
        raise ValueError(
            f"score scale must be one of {', '.join(SCALES)} or a pair LO,HI (got {scale!r})"
        ) from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ValueError(f"score scale LO,HI needs finite LO < HI (got {lo!r}, {hi!r})")
    return (lo, hi)


class ScoreCalibration:
    """Maps raw detection scores to the calibrated scale ``c ∈ [0, 1]`` (module docstring).

    Parameters
    ----------
    scale : {"auto", "prob"} or (lo, hi)
        The calibration.
    capacity : int
        ``"auto"`` only: the most scores kept (sorted); past it every second one is dropped.
    batch : int
        ``"auto"`` only: scores kept unsorted beside the sorted sample before they are merged
        into it (the calibration is the same; only its cost changes).

    Examples
    --------
    >>> cal = ScoreCalibration("auto")
    >>> cal([5.0, -1.0, 20.0, 2.0]).tolist()
    [0.75, 0.25, 1.0, 0.5]
    """

    def __init__(
        self, scale: str | tuple[float, float] = "auto", capacity: int = 8192, batch: int = 64
    ) -> None:
        self.scale = check_scale(scale)
        self.capacity = int(capacity)
        self.batch = int(batch)
        self.reset()

    def reset(self) -> None:
        """Forget the scores seen (and any priming)."""
        self._sorted = np.zeros(0)  # the scores seen, sorted, but the latest ones
        self._pending = np.empty(self.batch)  # the latest ones (first _n), unsorted
        self._n = 0
        self._primed = False

    def prime(self, scores: ArrayLike) -> None:
        """Calibrate on ``scores`` (e.g. every score of an offline run) and stop learning."""
        s = np.sort(np.asarray(scores, dtype=np.float64).reshape(-1))
        self._sorted = s[np.isfinite(s)]
        self._n = 0
        self._primed = True

    def __call__(self, scores: ArrayLike) -> FloatArray:
        """Calibrated scores of one frame (learning them first under ``"auto"``)."""
        s = np.asarray(scores, dtype=np.float64).reshape(-1)
        if self.scale == "prob":
            return np.clip(s, 0.0, 1.0)
        if isinstance(self.scale, tuple):
            lo, hi = self.scale
            return np.clip((s - lo) / (hi - lo), 0.0, 1.0)
        if not self._primed and s.size:
            self._learn(s)
        pending = self._pending[: self._n]
        n = self._sorted.size + self._n
        if n == 0:
            return np.ones_like(s)
        below = np.searchsorted(self._sorted, s, side="right")
        if self._n:
            below += np.searchsorted(np.sort(pending), s, side="right")  # #{pending <= s}
        return below / n  # c(s) = #{s_j <= s} / n

    def _learn(self, s: FloatArray) -> None:
        """Add ``s`` to the scores seen: to the pending ones, merged into the sorted sample
        once more than ``batch`` are pending (so a frame costs no copy of the sample)."""
        if self._n + s.size <= self.batch:
            self._pending[self._n : self._n + s.size] = s
            self._n += s.size
            return
        merged = np.concatenate([self._sorted, self._pending[: self._n], s])
        merged.sort()
        while merged.size > self.capacity:
            merged = merged[1::2]
        self._sorted, self._n = merged, 0


def duplicates(
    xy: FloatArray, wh: FloatArray, score: FloatArray, iou: float
) -> BoolArray:
    """Boxes that overlap a higher-scored box of the same frame by IoU ≥ ``iou``.

    Greedy non-maximum suppression: boxes are visited by decreasing score (ties by their
    position, left to right, then top to bottom, so the order of the rows does not matter); a
    box is a duplicate when a kept box overlaps it by ``iou`` or more.

    Parameters
    ----------
    xy, wh : (M, 2)
        Box centres and sizes.
    score : (M,)
        Scores (any monotone scale).
    iou : float
        Threshold in (0, 1].

    Returns
    -------
    (M,) bool
        True for the suppressed boxes.
    """
    m = xy.shape[0]
    dup = np.zeros(m, dtype=bool)
    if m < 2:
        return dup
    over = _overlap_at_least(xy[:, None], wh[:, None], xy, wh, iou)
    np.fill_diagonal(over, False)
    if not over.any():
        return dup
    order = np.lexsort((xy[:, 1], xy[:, 0], -score))
    rank = np.empty(m, dtype=np.intp)
    rank[order] = np.arange(m)
    # a loop over the boxes that overlap another one only (few), best first
    for i in order[over.any(axis=1)[order]]:
        if not dup[i]:
            dup |= over[i] & (rank > rank[i])
    return dup


def isolated(
    xy: FloatArray, wh: FloatArray, score: FloatArray, oxy: FloatArray, owh: FloatArray,
    iou: float,
) -> BoolArray:
    """Boxes that overlap none of some others and no better-scored one of themselves.

    A box is isolated when its IoU with every other box ``(oxy, owh)`` is below ``iou`` and it
    is not a :func:`duplicates` of a higher-scored box among the boxes so isolated. The test
    ``IoU ≥ t`` is ``|a ∩ b| (1 + t) ≥ t (|a| + |b|)``, without a division.

    Parameters
    ----------
    xy, wh : (M, 2)
        Box centres and sizes.
    score : (M,)
        Their scores (any monotone scale).
    oxy, owh : (K, 2)
        Centres and sizes of the other boxes (live tracks' predicted boxes, high detections).
    iou : float
        Threshold in (0, 1].

    Returns
    -------
    (M,) bool
    """
    keep = ~_overlaps_any(xy, wh, oxy, owh, iou) if oxy.shape[0] else np.ones(len(xy), bool)
    idx = keep.nonzero()[0]
    if idx.size > 1:  # of two overlapping candidates, the better-scored one
        keep[idx[duplicates(xy[idx], wh[idx], score[idx], iou)]] = False
    return keep


#: pairs of boxes tested densely by :func:`isolated`; above, only those whose centres are
#: close enough to overlap (a spatial grid)
DENSE_OVERLAP = 6_400


def _overlap_at_least(
    axy: FloatArray, awh: FloatArray, bxy: FloatArray, bwh: FloatArray, iou: float
) -> BoolArray:
    """``IoU(a, b) ≥ iou`` for boxes given by centres and sizes (broadcast against each other:
    a matrix, or aligned pairs), as ``|a ∩ b| (1 + t) ≥ t (|a| + |b|)`` with ``|a ∩ b| > 0``."""
    ahalf, bhalf = awh / 2, bwh / 2
    side = np.minimum(axy + ahalf, bxy + bhalf)
    side -= np.maximum(axy - ahalf, bxy - bhalf)
    np.maximum(side, 0.0, out=side)
    inter = side[..., 0] * side[..., 1]
    areas = awh[..., 0] * awh[..., 1] + bwh[..., 0] * bwh[..., 1]
    return (inter * (1.0 + iou) >= iou * areas) & (inter > 0)


def _overlaps_any(
    xy: FloatArray, wh: FloatArray, oxy: FloatArray, owh: FloatArray, iou: float
) -> BoolArray:
    """Whether each box overlaps some box ``(oxy, owh)`` by IoU ≥ ``iou``
    (:func:`_overlap_at_least`): every pair when there are few, else the pairs whose centres
    lie within the sum of the two half-diagonals (a spatial grid)."""
    m, k = xy.shape[0], oxy.shape[0]
    if m * k <= DENSE_OVERLAP:  # every pair, as an (M, K) matrix
        return _overlap_at_least(xy[:, None], wh[:, None], oxy, owh, iou).any(axis=1)
    half_diag = 0.5 * np.hypot(wh[:, 0], wh[:, 1])
    reach = half_diag + 0.5 * float(np.hypot(owh[:, 0], owh[:, 1]).max())
    a, b = spatial_pairs(xy, oxy, reach)
    # boxes apart along x cannot overlap: one cheap test drops most candidate pairs
    near = np.abs(xy[:, 0].take(a) - oxy[:, 0].take(b)) * 2.0 < (
        wh[:, 0].take(a) + owh[:, 0].take(b))
    a, b = a.compress(near), b.compress(near)
    hit = _overlap_at_least(xy.take(a, 0), wh.take(a, 0), oxy.take(b, 0), owh.take(b, 0), iou)
    out = np.zeros(m, dtype=bool)
    out[a.compress(hit)] = True
    return out
