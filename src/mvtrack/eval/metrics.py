"""MOTChallenge evaluation of one sequence: CLEAR-MOT, identity and HOTA metrics.

:func:`score_sequence` matches ground truth and predictions frame by frame on box IoU
(:mod:`~mvtrack.eval.iou`), then counts CLEAR-MOT and identity metrics with motmetrics'
algorithm (:mod:`~mvtrack.eval.clear`) and HOTA with TrackEval's
(:mod:`~mvtrack.eval.hota`); :func:`evaluate` returns the scores as a flat dict.

The ignore flag (7th column of a MOT15 ``gt.txt``: 1 = evaluate, 0 = ignore), ``ignore=``:

* ``"drop"`` (default) — rows with flag 0 are removed before scoring, so a box on such a
  person is a false positive. This is what the MOTChallenge devkit does for 2D MOT 2015
  (``evaluateTracking.m`` deletes the 0-marked rows; TrackEval skips its preprocessing for
  ``MOT15``), what motmetrics' ``eval_motchallenge`` does (``min_confidence=1``) and what
  ``peerbench`` does: scores comparable with published MOT15 numbers and with the peers.
* ``"distractor"`` — the devkit's preprocessing of MOT16/17/20 applied to the MOT15 flag:
  each frame's predictions are first matched to *all* ground-truth boxes (the greatest total
  IoU among pairs with IoU ≥ the threshold, as TrackEval), predictions matched to a 0-marked
  box are removed, then the 0-marked rows are removed. A box on an ignored person is then
  neither a hit nor a false positive.
* ``"none"`` — every row counts, whatever its flag.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from mvtrack.errors import InputError
from mvtrack.eval.assignment import max_weight_matching
from mvtrack.eval.checks import check_inputs
from mvtrack.eval.clear import ClearCounts, clear_counts
from mvtrack.eval.hota import HOTA_KEYS, HotaCounts, hota_counts
from mvtrack.eval.iou import BoxPairs, overlapping_pairs
from mvtrack.io.mot import MotTable, read_tracks

Ignore = Literal["drop", "distractor", "none"]
IGNORE_MODES: tuple[str, ...] = ("drop", "distractor", "none")
DEFAULT_IGNORE: Ignore = "drop"

_EPS = float(np.finfo(np.float64).eps)

#: Largest |ID| a MOTChallenge file can give exactly (the readers parse numbers as float64).
_ID_EXACT = 2**53


@dataclass(frozen=True)
class SequenceScores:
    """The counts of one sequence (or of several combined), and what was noticed on the way.

    Attributes
    ----------
    clear : ClearCounts
        CLEAR-MOT and identity counts.
    hota : HotaCounts or None
        HOTA counts (None when not computed).
    iou : float
        The IoU threshold of CLEAR-MOT and identity matching.
    ignore : str
        How the ignore flag was treated.
    num_ignored_gt : int
        Ground-truth rows not scored (flag 0, with ``drop`` and ``distractor``).
    num_ignored_pred : int
        Predictions removed because they matched an ignored person (``distractor``).
    notes : tuple of str
        Warnings about the inputs (suspicious but not impossible).
    """

    clear: ClearCounts
    hota: HotaCounts | None
    iou: float
    ignore: str
    num_ignored_gt: int = 0
    num_ignored_pred: int = 0
    notes: tuple[str, ...] = field(default=())

    def __add__(self, other: SequenceScores) -> SequenceScores:
        """Combine two sequences: summed counts, as the devkit and TrackEval combine them."""
        hota = None if self.hota is None or other.hota is None else self.hota + other.hota
        return SequenceScores(
            self.clear + other.clear, hota, self.iou,
            self.ignore if self.ignore == other.ignore else "mixed",
            self.num_ignored_gt + other.num_ignored_gt,
            self.num_ignored_pred + other.num_ignored_pred, self.notes + other.notes,
        )

    def as_dict(self) -> dict[str, Any]:
        """The flat dict returned by :func:`evaluate`."""
        c = self.clear
        out: dict[str, Any] = c.scores()
        out.update(
            IDSW=c.num_switches, FP=c.num_false_positives, FN=c.num_misses,
            MT=c.mostly_tracked, PT=c.partially_tracked, ML=c.mostly_lost,
            FM=c.num_fragmentations, IDTP=c.idtp, IDFP=c.num_pred_dets - c.idtp,
            IDFN=c.num_gt_dets - c.idtp, num_gt_ids=c.num_gt_ids, num_pred_ids=c.num_pred_ids,
            num_gt_dets=c.num_gt_dets, num_pred_dets=c.num_pred_dets,
            num_matches=c.num_matches, num_frames=c.num_frames, iou_threshold=float(self.iou),
            ignore=self.ignore, num_ignored_gt=self.num_ignored_gt,
            num_ignored_pred=self.num_ignored_pred,
        )
        hota = self.hota.scores() if self.hota is not None else dict.fromkeys(HOTA_KEYS)
        out.update(hota)
        out["notes"] = list(self.notes)
        return out


def read_table(path: str | os.PathLike[str], kind: Literal["gt", "results"]) -> MotTable:
    """Read a ground-truth or results file for scoring; IDs must be exact 64-bit integers.

    Raises
    ------
    InputError
        As :func:`mvtrack.io.mot.read_tracks`, and when an ID or frame number does not fit
        in a 64-bit integer, or an ID is ±2⁵³ or beyond (it may not have been read exactly).
    """
    with warnings.catch_warnings():
        # The readers cast float columns to int64; NumPy warns when a value does not fit.
        warnings.filterwarnings("error", "invalid value encountered in cast", RuntimeWarning)
        try:
            table = read_tracks(path, kind)
        except RuntimeWarning:
            raise InputError(
                f"{path}: an id or frame number is outside the 64-bit integer range"
            ) from None
    big = np.flatnonzero(np.abs(table.id) >= _ID_EXACT)
    if big.size:
        raise InputError(
            f"{path}: id {table.id[big[0]]} is 2^53 or more in magnitude and cannot be read "
            "exactly; renumber the ids"
        )
    return table


def _as_table(value: MotTable | str | os.PathLike[str], kind: Literal["gt", "results"]) -> MotTable:
    return value if isinstance(value, MotTable) else read_table(value, kind)


def _distractor_hits(gt: MotTable, pred: MotTable, pairs: BoxPairs, iou: float) -> np.ndarray:
    """Predictions matched to a 0-marked ground-truth box (TrackEval's MOT16+ preprocessing).

    Per frame, predictions are matched to every ground-truth box by the greatest total IoU
    among pairs with IoU ≥ ``iou`` (less machine ε, as TrackEval).
    """
    hit = np.zeros(len(pred), dtype=bool)
    ok = pairs.take(np.flatnonzero(pairs.iou >= iou - _EPS))
    for lo, hi in ok.frame_slices(gt.frame):
        if not (gt.conf[ok.a[lo:hi]] == 0).any():
            continue
        pick = lo + max_weight_matching(ok.a[lo:hi], ok.b[lo:hi], ok.iou[lo:hi])
        on_ignored = pick[gt.conf[ok.a[pick]] == 0]
        hit[ok.b[on_ignored]] = True
    return hit


def _restrict(pairs: BoxPairs, keep_a: np.ndarray, keep_b: np.ndarray) -> BoxPairs:
    """The pairs between kept rows, renumbered to the kept tables' rows."""
    new_a = np.cumsum(keep_a) - 1
    new_b = np.cumsum(keep_b) - 1
    sel = np.flatnonzero(keep_a[pairs.a] & keep_b[pairs.b])
    return BoxPairs(new_a[pairs.a[sel]], new_b[pairs.b[sel]], pairs.iou[sel])


def score_sequence(
    gt: MotTable | str | os.PathLike[str],
    pred: MotTable | str | os.PathLike[str],
    iou: float = 0.5,
    *,
    ignore: Ignore = DEFAULT_IGNORE,
    with_hota: bool = True,
    check: bool = True,
) -> SequenceScores:
    """Counts of ``pred`` against ``gt`` (see :func:`evaluate`)."""
    if not 0.0 < iou <= 1.0:
        raise ValueError(f"iou threshold must be in (0, 1], got {iou}")
    if ignore not in IGNORE_MODES:
        raise ValueError(f"ignore must be one of {', '.join(IGNORE_MODES)}, got {ignore!r}")
    # A reader's warnings (an empty file) wait for the checks: when the inputs are refused,
    # the refusal is the one line to show, and it names the problem itself.
    with warnings.catch_warnings(record=True) as read_warnings:
        warnings.simplefilter("always")
        gt_t, pred_t = _as_table(gt, "gt"), _as_table(pred, "results")
    notes: list[str] = []
    keep_gt = np.ones(len(gt_t), bool) if ignore == "none" else gt_t.conf != 0
    pairs = overlapping_pairs(gt_t.frame, gt_t.tlwh, pred_t.frame, pred_t.tlwh)
    if check:
        notes.extend(check_inputs(gt_t, pred_t, keep_gt, pairs, iou))
    for w in read_warnings:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    keep_pred = np.ones(len(pred_t), bool)
    if ignore == "distractor":
        keep_pred = ~_distractor_hits(gt_t, pred_t, pairs, iou)
    g, p = gt_t.take(keep_gt), pred_t.take(keep_pred)
    pairs = _restrict(pairs, keep_gt, keep_pred)
    num_frames = max(gt_t.num_frames, pred_t.num_frames)
    clear = clear_counts(g.frame, g.id, p.frame, p.id, pairs, iou, num_frames)
    hota = hota_counts(g.frame, g.id, p.id, pairs) if with_hota else None
    return SequenceScores(
        clear, hota, float(iou), ignore, int((~keep_gt).sum()), int((~keep_pred).sum()),
        tuple(notes),
    )


def evaluate(
    gt: MotTable | str | os.PathLike[str],
    pred: MotTable | str | os.PathLike[str],
    iou: float = 0.5,
    *,
    ignore: Ignore = DEFAULT_IGNORE,
    with_hota: bool = True,
    check: bool = True,
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
    ignore : {"drop", "distractor", "none"}
        How ground-truth rows with flag 0 are treated (see the module docstring).
    with_hota : bool
        Also compute HOTA.
    check : bool
        Check that the two inputs can belong together (:func:`~mvtrack.eval.checks.
        check_inputs`): raise :class:`~mvtrack.errors.InputError` where they cannot, add a
        note where they look suspicious.

    Returns
    -------
    dict
        ``MOTA``, ``MOTP`` (mean IoU of the matched pairs, higher is better, as in the
        MOTChallenge devkit; motmetrics' own ``motp`` is ``1 - MOTP``), ``IDF1``, ``IDP``,
        ``IDR``, ``IDSW``, ``FP``, ``FN``, ``MT``, ``PT``, ``ML``, ``FM``, ``IDTP``,
        ``IDFP``, ``IDFN``, ``precision``, ``recall``, ``num_gt_ids``, ``num_pred_ids``,
        ``num_gt_dets``, ``num_pred_dets``, ``num_matches``, ``num_frames``,
        ``iou_threshold``, ``ignore``, ``num_ignored_gt``, ``num_ignored_pred``; ``HOTA``,
        ``DetA``, ``AssA``, ``LocA``, ``DetRe``, ``DetPr``, ``AssRe``, ``AssPr`` (``None``
        when ``with_hota`` is False), and ``notes``, a list of warnings about the inputs.
    """
    return score_sequence(
        gt, pred, iou, ignore=ignore, with_hota=with_hota, check=check
    ).as_dict()
