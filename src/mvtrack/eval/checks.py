"""Checks that a ground truth and a results table can belong to the same sequence.

Scoring the results of one sequence against the ground truth of another gives numbers that
look like a bad tracker (MOTA −1.66) rather than an error. :func:`check_inputs` refuses what
cannot be right and returns warnings for what only looks wrong:

=====================================================  ============================
condition                                              outcome
=====================================================  ============================
ground truth without rows, or none left to score       refused (:class:`InputError`)
results and ground truth share no frame                refused
no result box intersects the extent of the gt boxes    refused
result rows after the last ground-truth frame          warning (they count as FP)
most result boxes outside the extent of the gt boxes   warning
almost no result box overlaps a gt box at the IoU      warning
the two files look swapped (:func:`swapped_note`)      warning
=====================================================  ============================

An empty results table is not refused: it scores MOTA 0 (every ground-truth box missed).
"""

from __future__ import annotations

import numpy as np

from mvtrack.errors import InputError
from mvtrack.eval.iou import BoxPairs
from mvtrack.io.mot import MotTable

#: Fraction of result boxes outside the ground-truth extent above which a warning is given.
OUTSIDE_WARN = 0.5
#: Below this fraction of result boxes with a valid pair, a warning is given ...
MATCHED_WARN = 0.05
#: ... when there are at least this many result boxes.
MATCHED_WARN_MIN_BOXES = 20


def _span(v: np.ndarray) -> str:
    return f"{v.min():.0f}–{v.max():.0f}"


def check_inputs(
    gt: MotTable, pred: MotTable, scored: np.ndarray, pairs: BoxPairs, iou: float
) -> list[str]:
    """Refuse inputs that cannot belong together; return warnings about suspicious ones.

    Parameters
    ----------
    gt, pred : MotTable
        Ground truth (all rows) and results.
    scored : (N,) bool
        The ground-truth rows that will be scored (after the ignore flag).
    pairs : BoxPairs
        Overlapping pairs of ``gt`` and ``pred`` (:func:`~mvtrack.eval.iou.overlapping_pairs`).
    iou : float
        The matching threshold.

    Raises
    ------
    InputError
        Ground truth without rows to score; results sharing no frame with the ground truth;
        no result box intersecting the extent of the ground-truth boxes.
    """
    if len(gt) == 0:
        raise InputError("the ground truth has no rows: nothing to evaluate")
    if not scored.any():
        raise InputError(
            f"all {len(gt)} ground-truth rows have the ignore flag (column 7) set to 0: "
            "nothing to evaluate (--ignore none scores them)"
        )
    if len(pred) == 0:
        return []
    gf, pf = gt.frame + 1, pred.frame + 1
    if len(pairs) == 0 and np.intersect1d(np.unique(pf), np.unique(gf)).size == 0:
        raise InputError(
            f"the results share no frame with the ground truth (ground truth frames "
            f"{_span(gf)}, results frames {_span(pf)}): not the same sequence?"
        )
    lo = gt.tlwh[:, :2].min(axis=0)
    hi = (gt.tlwh[:, :2] + gt.tlwh[:, 2:]).max(axis=0)
    p_lo, p_hi = pred.tlwh[:, :2], pred.tlwh[:, :2] + pred.tlwh[:, 2:]
    inside = ((p_hi > lo) & (p_lo < hi)).all(axis=1)
    extent = f"x {lo[0]:.0f}–{hi[0]:.0f}, y {lo[1]:.0f}–{hi[1]:.0f}"
    if not inside.any():
        raise InputError(
            f"no result box intersects the extent of the ground-truth boxes ({extent}; results "
            f"x {p_lo[:, 0].min():.0f}–{p_hi[:, 0].max():.0f}, y {p_lo[:, 1].min():.0f}–"
            f"{p_hi[:, 1].max():.0f}): another sequence, or boxes not in left, top, width, "
            "height?"
        )
    notes = []
    swapped = swapped_note(gt, pred)
    if swapped is not None:
        notes.append(swapped)
    late = int((pf > gf.max()).sum())
    if late:
        notes.append(
            f"{late} of {len(pred)} result rows lie after the last ground-truth frame "
            f"({gf.max()}); they count as false positives"
        )
    outside = int((~inside).sum())
    if outside > OUTSIDE_WARN * len(pred):
        notes.append(
            f"{outside} of {len(pred)} result boxes lie outside the extent of the ground-truth "
            f"boxes ({extent})"
        )
    valid = pairs.iou >= iou
    has_pair = np.zeros(len(pred), dtype=bool)
    has_pair[pairs.b[valid & scored[pairs.a]]] = True
    matched = int(has_pair.sum())
    if len(pred) >= MATCHED_WARN_MIN_BOXES and matched < MATCHED_WARN * len(pred):
        notes.append(
            f"only {matched} of {len(pred)} result boxes overlap a ground-truth box at IoU ≥ "
            f"{iou:g}: results of another sequence?"
        )
    return notes


def swapped_note(gt: MotTable, pred: MotTable) -> str | None:
    """A warning when the ground truth looks like results and the results like ground truth.

    Column 7 of a ground-truth file is a flag, 0 or 1 (MOT15 to MOT20); a results file puts
    a score there (often -1, or a confidence). Columns 8 and 9 of MOT16+ ground truth are a
    class (1, 2, ...) and a visibility in [0, 1]; a results file has -1 there (MOT15's ground
    truth too). So a "ground truth" with other values than 0 and 1 in column 7, or results
    with a class and a visibility on every row beside a ground truth without them, were
    probably given the other way round (``--gt`` and ``--pred`` swapped).
    """
    reasons = []
    scores = np.unique(gt.conf[(gt.conf != 0) & (gt.conf != 1)])
    if scores.size:
        reasons.append(f"the ground truth's column 7 holds scores such as {scores[0]:g}, not "
                       "the 0/1 flag of ground truth")
    truth_like = (len(pred) > 0 and bool((pred.cls >= 1).all())
                  and bool(((pred.visibility >= 0) & (pred.visibility <= 1)).all()))
    if truth_like and bool((gt.cls < 0).all()):
        reasons.append("the results have the class and visibility columns (8, 9) of ground "
                       "truth, the ground truth has none")
    if not reasons:
        return None
    return f"{'; '.join(reasons)}: are --gt and --pred swapped?"
