"""CLEAR-MOT (Bernardin & Stiefelhagen 2008) and identity (Ristani et al. 2016) counts.

The frame-by-frame matching is the algorithm of motmetrics' ``MOTAccumulator.update``
(motmetrics 1.4), which the MOTChallenge scoring scripts built on motmetrics use:

1. a ground-truth object keeps the prediction it was matched to last time if that pair is
   still valid in this frame (distance ``1 - IoU`` with ``IoU >= iou``); when two objects
   claim the same prediction, the first in the frame's order gets it;
2. the remaining objects and predictions are matched by the most pairs, then the least total
   distance (:func:`~mvtrack.eval.assignment.clear_matching`); a match whose object was last
   matched to another prediction is an ID switch;
3. objects left over are misses (FN), predictions left over are false positives (FP).

It runs on the sparse list of overlapping pairs (:func:`~mvtrack.eval.iou.overlapping_pairs`)
instead of one dense matrix per frame, with the state of every object in arrays, so its cost
grows with the boxes and not with their product. The counts and the ratios made from them
equal motmetrics' on the same input (``tests/eval/test_metrics.py`` checks them against
motmetrics' own accumulator on the MOT15 sequences).

Identity metrics: ``IDTP`` is the largest total, over a one-to-one pairing of ground-truth and
predicted IDs, of the frames in which the two IDs have a valid pair; motmetrics finds it with a
dense ``(G + H)²`` assignment, here it is the maximum-weight matching of the sparse
co-occurrence counts (the same optimum).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from mvtrack.eval.assignment import clear_matching, max_weight_matching
from mvtrack.eval.iou import BoxPairs
from mvtrack.types import IntArray

#: MT / ML thresholds on the fraction of its frames in which an object is matched.
MOSTLY_TRACKED = 0.8
MOSTLY_LOST = 0.2


@dataclass(frozen=True)
class ClearCounts:
    """The counts behind CLEAR-MOT and identity metrics of one sequence.

    They add up over sequences (:meth:`__add__`), as the MOTChallenge devkit combines
    sequences: the ratios of a combination are computed from its summed counts.
    """

    num_frames: int  #: frames 1 … N scored
    num_gt_dets: int  #: ground-truth boxes
    num_pred_dets: int  #: predicted boxes
    num_gt_ids: int  #: distinct ground-truth IDs
    num_pred_ids: int  #: distinct predicted IDs
    num_matches: int  #: matched boxes that kept their ID (motmetrics' MATCH)
    num_switches: int  #: matched boxes whose object changed prediction ID (SWITCH)
    num_false_positives: int  #: unmatched predictions
    num_misses: int  #: unmatched ground-truth boxes
    mostly_tracked: int  #: objects matched in ≥ 80 % of their frames
    partially_tracked: int  #: in 20 % … 80 %
    mostly_lost: int  #: in < 20 %
    num_fragmentations: int  #: matched → missed transitions inside an object's matched span
    distance_sum: float  #: Σ (1 - IoU) over the matched boxes
    idtp: int  #: identity true positives

    def __add__(self, other: ClearCounts) -> ClearCounts:
        a, b = asdict(self), asdict(other)
        return ClearCounts(**{k: a[k] + b[k] for k in a})

    @property
    def num_detections(self) -> int:
        """Matched ground-truth boxes (matches plus switches)."""
        return self.num_matches + self.num_switches

    def scores(self) -> dict[str, float]:
        """MOTA, MOTP (mean IoU of the matches), IDF1, IDP, IDR, precision, recall.

        The same expressions as motmetrics (``quiet_divide``: NaN or ±inf on a zero
        denominator).
        """
        n_obj, n_pred, det = self.num_gt_dets, self.num_pred_dets, self.num_detections
        idtp = float(self.idtp)
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.true_divide
            return {
                "MOTA": float(1.0 - q(self.num_misses + self.num_switches
                                      + self.num_false_positives, n_obj)),
                "MOTP": float(1.0 - q(self.distance_sum, det)),
                "IDF1": float(q(2 * idtp, n_obj + n_pred)),
                "IDP": float(q(idtp, idtp + (n_pred - idtp))),
                "IDR": float(q(idtp, idtp + (n_obj - idtp))),
                "precision": float(q(det, self.num_false_positives + det)),
                "recall": float(q(det, n_obj)),
            }


def clear_counts(
    gt_frame: IntArray,
    gt_id: IntArray,
    pred_frame: IntArray,
    pred_id: IntArray,
    pairs: BoxPairs,
    iou: float,
    num_frames: int,
) -> ClearCounts:
    """CLEAR-MOT and identity counts of one sequence.

    Parameters
    ----------
    gt_frame, gt_id : (N,) int
        Frame and ID of each ground-truth box (IDs unique within a frame).
    pred_frame, pred_id : (M,) int
        Frame and ID of each predicted box.
    pairs : BoxPairs
        The overlapping pairs (``a`` ground truth, ``b`` prediction), frame-major, in the
        file order of each side within a frame (:func:`~mvtrack.eval.iou.overlapping_pairs`).
    iou : float
        A pair is valid when its IoU ≥ ``iou``.
    num_frames : int
        Frames scored (reported only).
    """
    n_gt, n_pred = gt_frame.shape[0], pred_frame.shape[0]
    g_ids, gid = np.unique(gt_id, return_inverse=True)
    p_ids, pid = np.unique(pred_id, return_inverse=True)
    gid, pid = gid.reshape(-1), pid.reshape(-1)
    valid = pairs.take(np.flatnonzero(pairs.iou >= iou))
    a, b = valid.a, valid.b
    dist = 1.0 - valid.iou

    last = np.full(g_ids.size, -1, dtype=np.int64)  # prediction an object was last matched to
    matched_a = np.zeros(n_gt, dtype=bool)
    matched_b = np.zeros(n_pred, dtype=bool)
    switch_a = np.zeros(n_gt, dtype=bool)
    kept_a = np.zeros(n_gt, dtype=bool)  # matched in step 1 (its event comes first)
    dist_a = np.zeros(n_gt)
    for lo, hi in valid.frame_slices(gt_frame):
        fa, fb, fd = a[lo:hi], b[lo:hi], dist[lo:hi]
        # 1. Keep last frame's pairs that are still valid; first object in frame order wins.
        cont = np.flatnonzero(last[gid[fa]] == pid[fb])
        if cont.size:
            cont = cont[np.unique(fb[cont], return_index=True)[1]]
            matched_a[fa[cont]] = matched_b[fb[cont]] = kept_a[fa[cont]] = True
            dist_a[fa[cont]] = fd[cont]
            free = np.flatnonzero(~matched_a[fa] & ~matched_b[fb])
        else:
            free = np.arange(fa.size)
        # 2. The most pairs, then the least distance, among the rest.
        pick = free[clear_matching(fa[free], fb[free], fd[free])]
        ra, rb = fa[pick], fb[pick]
        o, h = gid[ra], pid[rb]
        switch_a[ra] = (last[o] >= 0) & (last[o] != h)
        last[o] = h
        matched_a[ra] = matched_b[rb] = True
        dist_a[ra] = fd[pick]

    n_det = int(matched_a.sum())
    n_switch = int(switch_a.sum())
    present = np.bincount(gid, minlength=g_ids.size).astype(np.float64)
    tracked = np.bincount(gid, weights=matched_a, minlength=g_ids.size)
    ratio = tracked / np.maximum(present, 1.0)
    mt = int((ratio >= MOSTLY_TRACKED).sum())
    ml = int((ratio < MOSTLY_LOST).sum())
    return ClearCounts(
        num_frames=int(num_frames),
        num_gt_dets=int(n_gt),
        num_pred_dets=int(n_pred),
        num_gt_ids=int(g_ids.size),
        num_pred_ids=int(p_ids.size),
        num_matches=n_det - n_switch,
        num_switches=n_switch,
        num_false_positives=int(n_pred - matched_b.sum()),
        num_misses=int(n_gt - n_det),
        mostly_tracked=mt,
        partially_tracked=int(g_ids.size - mt - ml),
        mostly_lost=ml,
        num_fragmentations=_fragmentations(gt_frame, gid, matched_a),
        distance_sum=_distance_sum(gt_frame, pred_frame, matched_a, matched_b, kept_a, dist_a),
        idtp=_idtp(gid, pid, a, b),
    )


def _fragmentations(frame: IntArray, gid: IntArray, matched: np.ndarray) -> int:
    """Matched → missed transitions of each object between its first and last match."""
    order = np.lexsort((frame, gid))
    g, s = gid[order], matched[order]
    pos = np.arange(g.size)
    last_match = np.full(int(g.max()) + 1 if g.size else 0, -1, dtype=np.int64)
    np.maximum.at(last_match, g[s], pos[s])
    k = np.flatnonzero((g[1:] == g[:-1]) & s[:-1] & ~s[1:]) + 1
    return int((k < last_match[g[k]]).sum())


def _distance_sum(
    gt_frame: IntArray,
    pred_frame: IntArray,
    matched_a: np.ndarray,
    matched_b: np.ndarray,
    kept_a: np.ndarray,
    dist_a: np.ndarray,
) -> float:
    """Σ (1 - IoU) of the matches, summed in the order of motmetrics' event table.

    Per frame its events are the kept matches, the new matches, the misses and the false
    positives, each in the frame's box order; the misses and false positives have no
    distance (0 in the sum). Summing in that order (NumPy's pairwise sum, as pandas does)
    reproduces motmetrics' MOTP to the last bit.
    """
    n_gt = gt_frame.shape[0]
    group = np.where(kept_a, 0, np.where(matched_a, 1, 2))
    frame = np.concatenate([gt_frame, pred_frame[~matched_b]])
    group = np.concatenate([group, np.full(int((~matched_b).sum()), 3)])
    pos = np.arange(frame.size)  # file order within a frame, ground truth before predictions
    values = np.concatenate([np.where(matched_a, dist_a, 0.0), np.zeros(frame.size - n_gt)])
    order = np.lexsort((pos, group, frame))
    return float(np.sum(values[order]))


def _idtp(gid: IntArray, pid: IntArray, a: IntArray, b: IntArray) -> int:
    """Identity true positives: maximum-weight matching of the ID co-occurrence counts."""
    if a.size == 0:
        return 0
    n_p = int(pid.max()) + 1
    keys, counts = np.unique(gid[a] * n_p + pid[b], return_counts=True)
    rows, cols = keys // n_p, keys % n_p
    pick = max_weight_matching(rows, cols, counts.astype(np.float64))
    return int(counts[pick].sum())
