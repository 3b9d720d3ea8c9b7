"""HOTA (Luiten et al., IJCV 2021), the algorithm of TrackEval's ``HOTA.eval_sequence``.

For each localisation threshold α ∈ {0.05, 0.10, …, 0.95}:

.. math::

    \\mathrm{DetA}_\\alpha = \\frac{|TP|}{|TP| + |FN| + |FP|}, \\qquad
    \\mathrm{AssA}_\\alpha = \\frac{1}{|TP|} \\sum_{c \\in TP}
        \\frac{|TPA(c)|}{|TPA(c)| + |FNA(c)| + |FPA(c)|}, \\qquad
    \\mathrm{HOTA}_\\alpha = \\sqrt{\\mathrm{DetA}_\\alpha \\, \\mathrm{AssA}_\\alpha}

and each score is the mean over α. The matching of a frame maximises
``A(g, t) · IoU`` where ``A`` is the global alignment of the two IDs over the sequence (their
summed per-frame Jaccard overlap over ``|g| + |t| - overlap``), as TrackEval does.

TrackEval solves one dense ``N × M`` assignment per frame and holds every frame's similarity
matrix at once (2.4 GB for 1 000 targets over 300 frames). Here the same quantities are built
from the sparse list of overlapping pairs and the assignment of a frame runs only where boxes
compete (:func:`~mvtrack.eval.assignment.max_weight_matching`). ``tests/eval/test_metrics.py``
checks the result against TrackEval's own MOTChallenge pipeline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.eval.assignment import max_weight_matching
from mvtrack.eval.iou import BoxPairs
from mvtrack.types import FloatArray, IntArray

#: TrackEval's localisation thresholds (``np.arange(0.05, 0.99, 0.05)``: 19 values).
ALPHAS: FloatArray = np.arange(0.05, 0.99, 0.05)

#: The HOTA family of scores reported (each averaged over the 19 α thresholds).
HOTA_KEYS: tuple[str, ...] = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr")

_EPS = float(np.finfo(np.float64).eps)


@dataclass(frozen=True)
class HotaCounts:
    """Per-α counts and association scores of one sequence (or a combination).

    ``assa``, ``assre``, ``asspr`` and ``loca`` are the sequence's per-α values; combining
    sequences weights them by ``tp``, as TrackEval's ``combine_sequences``.
    """

    tp: FloatArray
    fn: FloatArray
    fp: FloatArray
    assa: FloatArray
    assre: FloatArray
    asspr: FloatArray
    loca: FloatArray

    def __add__(self, other: HotaCounts) -> HotaCounts:
        tp = self.tp + other.tp
        w = np.maximum(1.0, tp)

        def av(x: FloatArray, y: FloatArray) -> FloatArray:
            return (x * self.tp + y * other.tp) / w

        loca = np.maximum(1e-10, self.loca * self.tp + other.loca * other.tp) / np.maximum(
            1e-10, tp
        )
        return HotaCounts(
            tp, self.fn + other.fn, self.fp + other.fp, av(self.assa, other.assa),
            av(self.assre, other.assre), av(self.asspr, other.asspr), loca,
        )

    def scores(self) -> dict[str, float]:
        """HOTA, DetA, AssA, LocA, DetRe, DetPr, AssRe, AssPr, each the mean over α."""
        det_re = self.tp / np.maximum(1.0, self.tp + self.fn)
        det_pr = self.tp / np.maximum(1.0, self.tp + self.fp)
        det_a = self.tp / np.maximum(1.0, self.tp + self.fn + self.fp)
        per_alpha = {
            "HOTA": np.sqrt(det_a * self.assa), "DetA": det_a, "AssA": self.assa,
            "LocA": self.loca, "DetRe": det_re, "DetPr": det_pr, "AssRe": self.assre,
            "AssPr": self.asspr,
        }
        return {key: float(np.mean(per_alpha[key])) for key in HOTA_KEYS}


def hota_counts(
    gt_frame: IntArray, gt_id: IntArray, pred_id: IntArray, pairs: BoxPairs
) -> HotaCounts:
    """HOTA counts of one sequence.

    Parameters
    ----------
    gt_frame, gt_id : (N,) int
        Frame and ID of each ground-truth box.
    pred_id : (M,) int
        ID of each predicted box.
    pairs : BoxPairs
        Every overlapping (ground truth, prediction) pair, frame-major
        (:func:`~mvtrack.eval.iou.overlapping_pairs`).
    """
    n_gt, n_pred, n_a = gt_id.shape[0], pred_id.shape[0], ALPHAS.size
    zeros = np.zeros(n_a)
    if n_pred == 0 or n_gt == 0:
        return HotaCounts(zeros, np.full(n_a, float(n_gt)), np.full(n_a, float(n_pred)),
                          zeros, zeros, zeros, np.ones(n_a))
    gid = np.unique(gt_id, return_inverse=True)[1].reshape(-1)
    pid = np.unique(pred_id, return_inverse=True)[1].reshape(-1)
    a, b, sim = pairs.a, pairs.b, pairs.iou
    gt_count = np.bincount(gid).astype(np.float64)
    pr_count = np.bincount(pid).astype(np.float64)

    # Global alignment of ID pairs from the per-frame Jaccard-normalised similarity.
    row_sum = np.bincount(a, weights=sim, minlength=n_gt)
    col_sum = np.bincount(b, weights=sim, minlength=n_pred)
    denom = col_sum[b] + row_sum[a] - sim
    sim_iou = np.zeros_like(sim)
    np.divide(sim, denom, out=sim_iou, where=denom > _EPS)
    n_p = pr_count.size
    keys, key_of_pair = np.unique(gid[a] * n_p + pid[b], return_inverse=True)
    key_of_pair = key_of_pair.reshape(-1)
    k_g, k_p = keys // n_p, keys % n_p
    potential = np.bincount(key_of_pair, weights=sim_iou, minlength=keys.size)
    alignment = potential / (gt_count[k_g] + pr_count[k_p] - potential)
    score = alignment[key_of_pair] * sim

    # Per frame: the pairs of greatest total score.
    chosen = [np.zeros(0, np.int64)]
    for lo, hi in pairs.frame_slices(gt_frame):
        chosen.append(lo + max_weight_matching(a[lo:hi], b[lo:hi], score[lo:hi]))
    pick = np.concatenate(chosen)
    m_sim, m_key = sim[pick], key_of_pair[pick]

    ok = m_sim[None, :] >= ALPHAS[:, None] - _EPS  # (α, matches)
    tp = ok.sum(axis=1).astype(np.float64)
    loca_sum = (ok * m_sim[None, :]).sum(axis=1)
    assa, assre, asspr = (np.zeros(n_a) for _ in range(3))
    for i in range(n_a):
        count = np.bincount(m_key[ok[i]], minlength=keys.size).astype(np.float64)
        hit = np.flatnonzero(count)
        c, g, p = count[hit], gt_count[k_g[hit]], pr_count[k_p[hit]]
        w = max(1.0, tp[i])
        assa[i] = np.sum(c * (c / np.maximum(1.0, g + p - c))) / w
        assre[i] = np.sum(c * (c / np.maximum(1.0, g))) / w
        asspr[i] = np.sum(c * (c / np.maximum(1.0, p))) / w
    loca = np.maximum(1e-10, loca_sum) / np.maximum(1e-10, tp)
    return HotaCounts(tp, n_gt - tp, n_pred - tp, assa, assre, asspr, loca)
