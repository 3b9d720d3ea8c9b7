"""CLEAR-MOT and identity metrics through motmetrics, HOTA through TrackEval.

:func:`evaluate` matches ground truth and predictions frame by frame on box IoU. The IoU
distance matrices are computed here (motmetrics 1.4's own ``iou_matrix`` and
``compare_to_groundtruth`` call ``np.asfarray``, which NumPy 2 removed) and fed to
``motmetrics.MOTAccumulator``; the pairing rule is the one of motmetrics'
``compare_to_groundtruth(..., "iou", distth=1 - iou)``: distance ``1 - IoU``, and a pair may
match only when ``IoU >= iou``.

All ground-truth rows count (no MOT16-style distractor classes or zero-flag rows are removed;
filter the table first if a dataset needs that).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from mvtrack.eval.hota import HOTA_KEYS, hota, trackeval_problem
from mvtrack.eval.iou import iou_matrix
from mvtrack.io.mot import MotTable, read_tracks

#: motmetrics metric name → our key.
_MOTMETRICS: dict[str, str] = {
    "mota": "MOTA",
    "motp": "MOTP",
    "idf1": "IDF1",
    "idp": "IDP",
    "idr": "IDR",
    "num_switches": "IDSW",
    "num_false_positives": "FP",
    "num_misses": "FN",
    "mostly_tracked": "MT",
    "partially_tracked": "PT",
    "mostly_lost": "ML",
    "num_fragmentations": "FM",
    "precision": "precision",
    "recall": "recall",
    "num_unique_objects": "num_gt_ids",
    "num_objects": "num_gt_dets",
    "num_predictions": "num_pred_dets",
    "num_matches": "num_matches",
}

_INT_KEYS = {
    "IDSW", "FP", "FN", "MT", "PT", "ML", "FM", "num_gt_ids", "num_gt_dets", "num_pred_dets",
    "num_matches", "num_pred_ids", "num_frames",
}


def _as_table(value: MotTable | str | os.PathLike[str], kind: str) -> MotTable:
    if isinstance(value, MotTable):
        return value
    return read_tracks(value, kind)  # type: ignore[arg-type]


def accumulate(gt: MotTable, pred: MotTable, iou: float = 0.5) -> Any:
    """A ``motmetrics.MOTAccumulator`` fed with IoU distances, one update per frame.

    Frames where either side has rows are visited, as in motmetrics'
    ``compare_to_groundtruth``; the distance is ``1 - IoU`` and NaN (no pairing) where
    ``IoU < iou``.
    """
    import motmetrics as mm

    if not 0.0 < iou <= 1.0:
        raise ValueError(f"iou threshold must be in (0, 1], got {iou}")
    n = max(gt.num_frames, pred.num_frames)
    g_idx, p_idx = gt.frame_index(n), pred.frame_index(n)
    acc = mm.MOTAccumulator(auto_id=False)
    for f in range(n):
        g, p = g_idx[f], p_idx[f]
        if g.size == 0 and p.size == 0:
            continue
        overlap = iou_matrix(gt.tlwh[g], pred.tlwh[p])
        dist = np.where(overlap >= iou, 1.0 - overlap, np.nan)
        acc.update(gt.id[g], pred.id[p], dist, frameid=f)
    return acc


def evaluate(
    gt: MotTable | str | os.PathLike[str],
    pred: MotTable | str | os.PathLike[str],
    iou: float = 0.5,
    *,
    with_hota: bool = True,
) -> dict[str, Any]:
    """MOTChallenge metrics of ``pred`` against ``gt``.

    Parameters
    ----------
    gt : MotTable or path
        Ground truth (a path is read as a ``gt`` file).
    pred : MotTable or path
        Tracker output (a path is read as a ``results`` file).
    iou : float
        Minimum IoU for a GT box and a predicted box to match (CLEAR-MOT and identity
        metrics; HOTA integrates over its own thresholds).
    with_hota : bool
        Also compute HOTA through TrackEval.

    Returns
    -------
    dict
        ``MOTA``, ``MOTP`` (mean IoU of the matched pairs, higher is better, as in the
        MOTChallenge devkit; motmetrics' own ``motp`` is ``1 - MOTP``), ``IDF1``, ``IDP``,
        ``IDR``, ``IDSW``, ``FP``, ``FN``, ``MT``, ``PT``, ``ML``, ``FM``, ``precision``,
        ``recall``, ``num_gt_ids``, ``num_pred_ids``, ``num_gt_dets``, ``num_pred_dets``,
        ``num_matches``, ``num_frames``, ``iou_threshold``; ``HOTA``, ``DetA``, ``AssA``,
        ``LocA``, ``DetRe``, ``DetPr``, ``AssRe``, ``AssPr`` (``None`` when TrackEval is
        unavailable or ``with_hota`` is False), and ``notes``, a list of strings.
    """
    import motmetrics as mm

    gt_t, pred_t = _as_table(gt, "gt"), _as_table(pred, "results")
    acc = accumulate(gt_t, pred_t, iou)
    mh = mm.metrics.create()
    raw = mh.compute(acc, metrics=list(_MOTMETRICS), return_dataframe=False, name="seq")
    out: dict[str, Any] = {}
    for name, key in _MOTMETRICS.items():
        value = float(raw[name])
        out[key] = round(value) if key in _INT_KEYS else value
    out["MOTP"] = 1.0 - out["MOTP"]  # motmetrics reports the mean distance 1 - IoU
    out["num_pred_ids"] = int(np.unique(pred_t.id).size)
    out["num_frames"] = max(gt_t.num_frames, pred_t.num_frames)
    out["iou_threshold"] = float(iou)
    notes: list[str] = []
    scores = hota(gt_t, pred_t) if with_hota else None
    if with_hota and scores is None:
        notes.append(trackeval_problem() or "HOTA not computed")
    for key in HOTA_KEYS:
        out[key] = None if scores is None else scores[key]
    out["notes"] = notes
    return out
