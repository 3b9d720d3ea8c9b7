"""HOTA (Luiten et al., IJCV 2021) through TrackEval's metric class on a data dict we build.

TrackEval's dataset loaders want files in its own folder layout; its metric classes only need,
per timestep, the GT and tracker IDs (remapped to ``0..K-1``) and the GT × tracker similarity
matrix (box IoU here). The metric class is TrackEval 1.3.0's own, kept verbatim in
:mod:`mvtrack._vendor.trackeval` (TrackEval's package cannot be a dependency: it declares
``opencv-python``). Should it fail to import, :func:`hota` returns ``None`` and
:func:`trackeval_problem` says why.
"""

from __future__ import annotations

import contextlib
import functools
import io
from typing import Any

import numpy as np

from mvtrack.eval.iou import iou_matrix
from mvtrack.io.mot import MotTable

#: The HOTA family of scores reported (each averaged over TrackEval's 19 α thresholds).
HOTA_KEYS: tuple[str, ...] = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr")


@functools.cache
def _import_hota() -> tuple[Any, str | None]:
    """TrackEval's HOTA class, importing it quietly (it prints about missing pycocotools)."""
    sink = io.StringIO()
    try:
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            from mvtrack._vendor.trackeval.metrics import HOTA
    except Exception as exc:  # any import-time failure means: no HOTA, say why
        return None, f"HOTA not computed: trackeval could not be imported ({exc})"
    return HOTA, None


def trackeval_problem() -> str | None:
    """Why HOTA is unavailable, or ``None`` when TrackEval imports."""
    return _import_hota()[1]


def hota_data(gt: MotTable, pred: MotTable) -> dict[str, Any]:
    """The per-sequence data dict of TrackEval's ``HOTA.eval_sequence``.

    Timesteps are the frames ``0 .. T-1`` with ``T`` the last frame of either table plus one;
    IDs of each side are remapped to ``0..K-1`` in increasing order.
    """
    n = max(gt.num_frames, pred.num_frames)
    gt_ids = np.unique(gt.id, return_inverse=True)[1].reshape(-1)
    tr_ids = np.unique(pred.id, return_inverse=True)[1].reshape(-1)
    g_idx, p_idx = gt.frame_index(n), pred.frame_index(n)
    return {
        "num_timesteps": n,
        "num_gt_ids": int(np.unique(gt.id).size),
        "num_tracker_ids": int(np.unique(pred.id).size),
        "num_gt_dets": len(gt),
        "num_tracker_dets": len(pred),
        "gt_ids": [gt_ids[g] for g in g_idx],
        "tracker_ids": [tr_ids[p] for p in p_idx],
        "similarity_scores": [
            iou_matrix(gt.tlwh[g], pred.tlwh[p]) for g, p in zip(g_idx, p_idx, strict=True)
        ],
    }


def hota(gt: MotTable, pred: MotTable) -> dict[str, float] | None:
    """HOTA, DetA, AssA, LocA (and the Re/Pr parts), each the mean over α = 0.05 … 0.95.

    .. math:: \\mathrm{HOTA}_\\alpha = \\sqrt{\\mathrm{DetA}_\\alpha\\,\\mathrm{AssA}_\\alpha}

    Returns ``None`` when TrackEval is not importable (see :func:`trackeval_problem`).
    """
    cls, _ = _import_hota()
    if cls is None:
        return None
    res = cls().eval_sequence(hota_data(gt, pred))
    return {key: float(np.mean(res[key])) for key in HOTA_KEYS}
