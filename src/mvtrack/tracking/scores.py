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
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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
