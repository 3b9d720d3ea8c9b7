r"""Blob reasoning with the tracker: split blobs that hold several objects, merge fragments.

A foreground blob is not an object: two people walking side by side are one blob, a person
whose trousers match the pavement is two. Given the boxes the tracker predicts for its
confirmed tracks and the scene's size prior (:class:`~mvtrack.detection.sizeprior.SizePrior`),
:func:`split_merge` turns the blobs of one frame into object boxes:

1. **merge** — blobs that lie mostly (``inside`` of their area) within one predicted box and
   within no other are fragments of that object: their union is one box, if it is not much
   larger than the prediction;
2. **split by the tracks** — a blob into which ``k ≥ 2`` predicted boxes fall (each with
   ``cover`` of its area inside the blob) is divided among them: each foreground pixel goes to
   the track whose predicted centre is nearest in units of the predicted size,

   .. math:: j^*(p) = \arg\min_j \big((x_p - x_j)/w_j\big)^2 + \big((y_p - y_j)/h_j\big)^2,

   and each part's box is the extent of its pixels (the predicted box, clipped to the blob,
   for a part too small to measure: an occluded person);
3. **split by the size prior** — a blob ``w / w(y) ≥ wide`` times as wide as an object at its
   foot row, that the tracks did not split, is cut into ``k = round(w / w(y))`` parts at the
   emptiest columns of its foreground near the equally spaced cuts.

Every output box carries a flag: :data:`PLAIN`, :data:`MERGED` or :data:`SPLIT`.

Boxes are ``(left, top, width, height)`` with pixel ``(col, row)`` covering
``[col - 0.5, col + 0.5)`` (the convention of :mod:`mvtrack.detection.blobs`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.sizeprior import SizePrior

FloatArray = NDArray[np.float64]

PLAIN = 0  #: the box of one blob, as found
MERGED = 1  #: the union of fragments inside one predicted box
SPLIT = 2  #: one part of a blob that held several objects

FLAG_NAMES = {PLAIN: "plain", MERGED: "merged", SPLIT: "split"}


def _overlap(a: FloatArray, b: FloatArray) -> FloatArray:
    """(M, N) intersection areas of boxes ``a`` (M, 4) and ``b`` (N, 4), tlwh."""
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    return np.clip(hi - lo, 0.0, None).prod(axis=2)


def merge_fragments(
    boxes: FloatArray, predicted: FloatArray, inside: float = 0.6, grow: float = 1.4
) -> tuple[FloatArray, NDArray[np.int8]]:
    """Step 1: union of the blobs that lie inside one predicted box only.

    Parameters
    ----------
    boxes : (M, 4)
        Blob boxes.
    predicted : (N, 4)
        Predicted boxes of the confirmed tracks.
    inside : float
        Fraction of a blob's box area within a predicted box for it to belong to that box.
    grow : float
        A union wider or taller than ``grow`` times its predicted box is not merged.

    Returns
    -------
    boxes : (M', 4), flags : (M',) int8
        Merged boxes (flag :data:`MERGED`) first, then the untouched blobs (:data:`PLAIN`).
    """
    m = len(boxes)
    flags = np.zeros(m, np.int8)
    if m < 2 or len(predicted) == 0:
        return boxes, flags
    frac = _overlap(boxes, predicted) / np.maximum(boxes[:, 2:].prod(axis=1), 1e-9)[:, None]
    member = frac >= inside
    single = member.sum(axis=1) == 1
    owner = np.where(single, member.argmax(axis=1), -1)
    count = np.bincount(owner[single], minlength=len(predicted))
    cand = single & (count[np.maximum(owner, 0)] >= 2)
    if not cand.any():
        return boxes, flags
    n = len(predicted)
    lo = np.full((n, 2), np.inf)
    hi = np.full((n, 2), -np.inf)
    np.minimum.at(lo, owner[cand], boxes[cand, :2])
    np.maximum.at(hi, owner[cand], boxes[cand, :2] + boxes[cand, 2:])
    groups = np.flatnonzero(count >= 2)
    union = np.column_stack([lo[groups], hi[groups] - lo[groups]])
    ok = (union[:, 2:] <= grow * predicted[groups, 2:]).all(axis=1)
    merged_groups = groups[ok]
    gone = cand & np.isin(owner, merged_groups)
    out = np.concatenate([union[ok], boxes[~gone]])
    out_flags = np.concatenate([np.full(int(ok.sum()), MERGED, np.int8), flags[~gone]])
    return out, out_flags


def _pixels(mask: NDArray[np.uint8], box: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Columns and rows (image coordinates) of the foreground pixels inside ``box``."""
    h, w = mask.shape
    c0 = max(int(np.floor(box[0] + 0.5)), 0)
    r0 = max(int(np.floor(box[1] + 0.5)), 0)
    c1 = min(int(np.ceil(box[0] + box[2] - 0.5)), w)
    r1 = min(int(np.ceil(box[1] + box[3] - 0.5)), h)
    rr, cc = np.nonzero(mask[r0:r1, c0:c1])
    return cc.astype(np.float64) + c0, rr.astype(np.float64) + r0


def _extent(cols: FloatArray, rows: FloatArray) -> FloatArray:
    return np.array(
        [cols.min() - 0.5, rows.min() - 0.5, cols.max() - cols.min() + 1, rows.max() - rows.min() + 1]
    )


def split_by_tracks(
    box: FloatArray, mask: NDArray[np.uint8], predicted: FloatArray, min_part: float = 0.15
) -> FloatArray:
    """Step 2 for one blob: its foreground divided among the ``k`` predicted boxes in it.

    Returns (k, 4) boxes, one per predicted box, in the order given.
    """
    cols, rows = _pixels(mask, box)
    k = len(predicted)
    centre = predicted[:, :2] + predicted[:, 2:] / 2
    if cols.size == 0:
        return predicted.copy()
    dx = (cols[:, None] - centre[None, :, 0]) / predicted[None, :, 2]
    dy = (rows[:, None] - centre[None, :, 1]) / predicted[None, :, 3]
    who = np.argmin(dx * dx + dy * dy, axis=1)
    out = np.empty((k, 4))
    count = np.bincount(who, minlength=k)
    for j in range(k):  # k objects of one blob (two or three), not the frame's targets
        sel = who == j
        if count[j] < min_part * predicted[j, 2] * predicted[j, 3]:
            lo = np.maximum(predicted[j, :2], box[:2])
            hi = np.minimum(predicted[j, :2] + predicted[j, 2:], box[:2] + box[2:])
            out[j] = [*lo, *np.maximum(hi - lo, 1.0)]
        else:
            out[j] = _extent(cols[sel], rows[sel])
    return out


def split_by_width(box: FloatArray, mask: NDArray[np.uint8], k: int) -> FloatArray:
    """Step 3 for one blob: ``k`` parts cut at the emptiest columns near ``left + i w / k``."""
    cols, rows = _pixels(mask, box)
    if cols.size == 0 or k < 2:
        return box[None, :].copy()
    c0 = int(cols.min())
    width = int(cols.max()) - c0 + 1
    profile = np.bincount((cols - c0).astype(np.int64), minlength=width).astype(np.float64)
    profile = np.convolve(profile, np.ones(3) / 3, mode="same")
    step = width / k
    reach = max(int(0.3 * step), 1)
    cuts = [0]
    for i in range(1, k):  # k − 1 cuts of one blob
        nominal = int(round(i * step))
        lo, hi = max(nominal - reach, cuts[-1] + 1), min(nominal + reach, width - 1)
        cuts.append(lo + int(np.argmin(profile[lo : hi + 1])) if hi >= lo else nominal)
    cuts.append(width)
    parts = []
    rel = cols - c0
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        sel = (rel >= a) & (rel < b)
        if sel.any():
            parts.append(_extent(cols[sel], rows[sel]))
    return np.array(parts) if parts else box[None, :].copy()


def split_merge(
    blobs: FloatArray,
    mask: NDArray[np.uint8],
    predicted_boxes: FloatArray | None = None,
    size_prior: SizePrior | None = None,
    *,
    inside: float = 0.6,
    cover: float = 0.5,
    wide: float = 1.7,
    max_parts: int = 6,
) -> tuple[FloatArray, NDArray[np.int8]]:
    """Object boxes from the blobs of one frame (module docstring, steps 1–3).

    Parameters
    ----------
    blobs : (M, 4) float
        Blob boxes ``(left, top, width, height)`` in the coordinates of ``mask``.
    mask : (H, W) uint8
        The cleaned foreground mask the blobs come from (non-zero = foreground).
    predicted_boxes : (N, 4) float or None
        The boxes the tracker predicts for its confirmed tracks in this frame.
    size_prior : SizePrior or None
        The scene's size prior; step 3 runs only when it is ready.
    inside : float
        Step 1's share of a fragment inside its predicted box.
    cover : float
        Step 2's share of a predicted box inside a blob for the track to claim part of it.
    wide : float
        Step 3's width, relative to the prior's, from which a blob is cut.
    max_parts : int
        Most parts step 3 cuts a blob into.

    Returns
    -------
    boxes : (K, 4) float64
        Object boxes.
    flags : (K,) int8
        :data:`PLAIN`, :data:`MERGED` or :data:`SPLIT` per box.
    """
    boxes = np.asarray(blobs, np.float64).reshape(-1, 4)
    pred = (
        np.zeros((0, 4))
        if predicted_boxes is None
        else np.asarray(predicted_boxes, np.float64).reshape(-1, 4)
    )
    pred = pred[(pred[:, 2] > 0) & (pred[:, 3] > 0) & np.isfinite(pred).all(axis=1)]
    boxes, flags = merge_fragments(boxes, pred, inside)
    if len(boxes) == 0:
        return boxes, flags
    k_of = np.zeros(len(boxes), np.int64)
    if len(pred):
        share = _overlap(boxes, pred) / np.maximum(pred[:, 2:].prod(axis=1), 1e-9)[None, :]
        home = share.argmax(axis=0)  # the blob holding most of each predicted box
        claims = share[home, np.arange(len(pred))] >= cover
        k_of = np.bincount(home[claims], minlength=len(boxes))
    wide_k = np.zeros(len(boxes), np.int64)
    if size_prior is not None and size_prior.ready:
        r = size_prior.ratio(boxes)[:, 0]
        wide_k = np.where(r >= wide, np.minimum(np.round(r), max_parts), 0).astype(np.int64)
    todo = np.flatnonzero((k_of >= 2) | (wide_k >= 2))
    if todo.size == 0:
        return boxes, flags
    keep = np.ones(len(boxes), bool)
    keep[todo] = False
    new = [boxes[keep]]
    new_flags = [flags[keep]]
    for i in todo.tolist():  # the few blobs that hold several objects
        if k_of[i] >= 2:
            mine = np.flatnonzero(claims & (home == i))
            parts = split_by_tracks(boxes[i], mask, pred[mine])
        else:
            parts = split_by_width(boxes[i], mask, int(wide_k[i]))
        new.append(parts)
        new_flags.append(np.full(len(parts), SPLIT if len(parts) > 1 else flags[i], np.int8))
    return np.concatenate(new), np.concatenate(new_flags)
