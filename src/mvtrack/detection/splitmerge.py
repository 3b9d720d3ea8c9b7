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

import itertools

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.sizeprior import SizePrior
from mvtrack.jit import kernel

FloatArray = NDArray[np.float64]

PLAIN = 0  #: the box of one blob, as found
MERGED = 1  #: the union of fragments inside one predicted box
SPLIT = 2  #: one part of a blob that held several objects

FLAG_NAMES = {PLAIN: "plain", MERGED: "merged", SPLIT: "split"}

#: column share below which a part's columns are trimmed (:func:`_extent`), as the scene
#: front end trims its blobs
TRIM = 0.2

#: a second head must be at least this share of the tallest column's height (split_by_width)
HEADS = 0.8


def _overlap(a: FloatArray, b: FloatArray) -> FloatArray:
    """(M, N) intersection areas of boxes ``a`` (M, 4) and ``b`` (N, 4), tlwh."""
    a = np.ascontiguousarray(a, np.float64).reshape(-1, 4)
    b = np.ascontiguousarray(b, np.float64).reshape(-1, 4)
    out = np.empty((a.shape[0], b.shape[0]))
    overlap_areas(a, b, out)
    return out


@kernel
def overlap_areas(a: FloatArray, b: FloatArray, out: FloatArray) -> None:
    """``out[i, j]``: the intersection area of boxes ``a[i]`` and ``b[j]`` (tlwh), the
    product of the overlaps along x and y, each ``min(right) − max(left)`` clipped at 0 (NaN
    in, NaN out, as NumPy's ``maximum``, ``minimum`` and ``clip``)."""
    for i in range(a.shape[0]):
        for j in range(b.shape[0]):
            area = 1.0
            for c in range(2):
                lo_a, lo_b = a[i, c], b[j, c]
                hi_a, hi_b = lo_a + a[i, c + 2], lo_b + b[j, c + 2]
                lo = lo_a if (lo_a > lo_b or lo_a != lo_a) else lo_b
                hi = hi_a if (hi_a < hi_b or hi_a != hi_a) else hi_b
                d = hi - lo
                if d < 0.0:
                    d = 0.0
                area = d if c == 0 else area * d
            out[i, j] = area


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


def merge_stacked(
    boxes: FloatArray,
    flags: NDArray[np.int8],
    prior: SizePrior,
    overlap: float = 0.5,
    tall: float = 1.25,
    broad: float = 1.4,
) -> tuple[FloatArray, NDArray[np.int8]]:
    """Merge blobs stacked one above the other into one object of the prior's size.

    A person whose belt or trousers match the background falls apart into pieces one above
    the other. Two blobs are joined when their columns overlap by ``overlap`` of the narrower
    one and their union is at most ``tall`` times the expected height and ``broad`` times the
    expected width at its foot row; joined pairs are grouped transitively
    (``scipy.sparse.csgraph.connected_components``) and each group that still fits becomes its
    union, flagged :data:`MERGED`.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(boxes)
    if m < 2 or not prior.ready:
        return boxes, flags
    lo, hi = boxes[:, :2], boxes[:, :2] + boxes[:, 2:]
    ov = np.minimum(hi[:, None, 0], hi[None, :, 0]) - np.maximum(lo[:, None, 0], lo[None, :, 0])
    ov = np.clip(ov, 0.0, None)
    narrow = np.minimum(boxes[:, None, 2], boxes[None, :, 2])
    ulo = np.minimum(lo[:, None, :], lo[None, :, :])
    uhi = np.maximum(hi[:, None, :], hi[None, :, :])
    exp = prior.expected(uhi[..., 1].ravel()).reshape(m, m, 2)
    ok = (ov >= overlap * narrow) & ((uhi - ulo) <= exp * np.array([broad, tall])).all(axis=2)
    np.fill_diagonal(ok, False)
    if not ok.any():
        return boxes, flags
    i, j = np.nonzero(ok)
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(m, m))
    n, comp = connected_components(graph, directed=False)
    size = np.bincount(comp, minlength=n)
    glo = np.full((n, 2), np.inf)
    ghi = np.full((n, 2), -np.inf)
    np.minimum.at(glo, comp, lo)
    np.maximum.at(ghi, comp, hi)
    union = np.column_stack([glo, ghi - glo])
    fits = (union[:, 2:] <= prior.expected(ghi[:, 1]) * np.array([broad, tall])).all(axis=1)
    joined = (size >= 2) & fits
    gone = joined[comp]
    out = np.concatenate([union[joined], boxes[~gone]])
    out_flags = np.concatenate([np.full(int(joined.sum()), MERGED, np.int8), flags[~gone]])
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


def _extent(cols: FloatArray, rows: FloatArray, trim: float = TRIM) -> FloatArray:
    """Box of the pixels, without the columns holding less than ``trim`` of the fullest
    column's pixels (the low tail of a cast shadow)."""
    if trim > 0 and cols.size:
        c = (cols - cols.min()).astype(np.int64)
        count = np.bincount(c)
        full = count >= trim * count.max()
        sel = full[c]
        cols, rows = cols[sel], rows[sel]
    c0, r0 = cols.min(), rows.min()
    return np.array([c0 - 0.5, r0 - 0.5, cols.max() - c0 + 1, rows.max() - r0 + 1])


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


def split_by_width(
    box: FloatArray, mask: NDArray[np.uint8], k: int, valley: float = 0.85
) -> FloatArray:
    """Step 3 for one blob: up to ``k`` parts, cut where the silhouette dips between heads.

    The silhouette height of column ``c`` is the blob's bottom minus the top-most foreground
    row of the column. Near each equally spaced cut ``left + i w / k`` (within 30 % of a
    part's width) the lowest column is the candidate cut; it is kept only if it is at most
    ``valley`` times the lower of the highest columns on either side, and that lower one is
    at least :data:`HEADS` of the blob's highest column (two heads of like height with a dip
    between them), so a single wide walker (an arm or a bag out to one side) is not cut.
    """
    cols, rows = _pixels(mask, box)
    if cols.size == 0 or k < 2:
        return box[None, :].copy()
    c0 = int(cols.min())
    width = int(cols.max()) - c0 + 1
    rel = (cols - c0).astype(np.int64)
    top = np.full(width, np.inf)
    np.minimum.at(top, rel, rows)
    bottom = rows.max()
    height = np.where(np.isfinite(top), bottom - top + 1, 0.0)
    height = np.convolve(height, np.ones(3) / 3, mode="same")
    step = width / k
    reach = max(int(0.3 * step), 1)
    cuts = [0]
    for i in range(1, k):  # k − 1 cuts of one blob
        nominal = round(i * step)
        lo, hi = max(nominal - reach, cuts[-1] + 1), min(nominal + reach, width - 2)
        if hi < lo:
            continue
        cut = lo + int(np.argmin(height[lo : hi + 1]))
        left_peak = height[cuts[-1] : cut].max(initial=0.0)
        right_peak = height[cut + 1 : min(cut + 1 + int(step), width)].max(initial=0.0)
        lower_peak = min(left_peak, right_peak)
        if height[cut] <= valley * lower_peak and lower_peak >= HEADS * height.max():
            cuts.append(cut)
    cuts.append(width)
    if len(cuts) == 2:
        return box[None, :].copy()
    parts = []
    for a, b in itertools.pairwise(cuts):
        sel = (rel >= a) & (rel < b)
        if sel.any():
            parts.append(_extent(cols[sel], rows[sel]))
    return np.array(parts) if parts else box[None, :].copy()


#: two predicted boxes sharing this much of the smaller one's area are one (:func:`distinct_boxes`)
SAME = 0.5


@kernel
def distinct_boxes(pred: FloatArray, same: float) -> FloatArray:
    """Predicted boxes (tlwh, C-contiguous) without duplicates: of two boxes that share
    ``same`` of the smaller one's area (two tracks on one object, or on a part and the whole),
    the larger is kept, and of two of equal area the earlier."""
    m = pred.shape[0]
    if m < 2:
        return pred.copy()
    area = pred[:, 2] * pred[:, 3]
    inter = np.empty((m, m))
    overlap_areas(pred, pred, inter)
    drop = np.zeros(m, np.bool_)
    for a in range(m):
        for b in range(m):
            if a == b:
                continue
            smaller = area[a] < area[b] or (area[a] == area[b] and a > b)
            if smaller and inter[a, b] / min(area[a], area[b]) >= same:
                drop[a] = True
                break
    out = np.empty((m - drop.sum(), 4))
    i = 0
    for a in range(m):
        if not drop[a]:
            out[i] = pred[a]
            i += 1
    return out


def usable_predictions(
    predicted_boxes: FloatArray | None, size_prior: SizePrior | None = None, wide: float = 1.8
) -> FloatArray:
    """The predicted boxes the split uses: finite, of positive size, not a track that follows
    a blob of two (``max(wide, 1.8)`` times as wide as the prior's object, when it is ready)
    and without duplicates (:func:`distinct_boxes`)."""
    pred = (
        np.zeros((0, 4))
        if predicted_boxes is None
        else np.asarray(predicted_boxes, np.float64).reshape(-1, 4)
    )
    pred = pred[(pred[:, 2] > 0) & (pred[:, 3] > 0) & np.isfinite(pred).all(axis=1)]
    if size_prior is not None and size_prior.ready and len(pred):
        # a track that follows a blob of two people predicts a box of two: not one object
        pred = pred[size_prior.ratio(pred)[:, 0] < max(wide, 1.8)]
    return distinct_boxes(np.ascontiguousarray(pred), SAME)


def blob_claims(
    boxes: FloatArray, pred: FloatArray, cover: float
) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """For each predicted box, the blob holding most of it (``home``) and whether that blob
    holds ``cover`` of its area (the track claims part of the blob, step 2)."""
    share = _overlap(boxes, pred) / np.maximum(pred[:, 2:].prod(axis=1), 1e-9)[None, :]
    home = share.argmax(axis=0)
    return home, share[home, np.arange(len(pred))] >= cover


def split_merge(
    blobs: FloatArray,
    mask: NDArray[np.uint8],
    predicted_boxes: FloatArray | None = None,
    size_prior: SizePrior | None = None,
    *,
    inside: float = 0.6,
    cover: float = 0.5,
    wide: float = 1.8,
    max_parts: int = 6,
    valley: float = 0.85,
    tall: float = 0.7,
    merge: bool = True,
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
        Step 3's width, relative to the prior's, from which a blob is cut; predicted boxes
        ``max(wide, 1.8)`` times as wide are not used (a track on a blob of two).
    valley : float
        Step 3's dip of the silhouette (:func:`split_by_width`).
    tall : float
        Step 3 cuts only blobs at least this share of the expected height (a low, wide blob
        is clutter, not people side by side).
    merge : bool
        Run step 1 (``False``: the blobs are only divided, never joined).
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
    pred = usable_predictions(predicted_boxes, size_prior, wide)
    if merge:
        boxes, flags = merge_fragments(boxes, pred, inside)
    else:
        flags = np.zeros(len(boxes), np.int8)
    if size_prior is not None:
        boxes, flags = merge_stacked(boxes, flags, size_prior)
    if len(boxes) == 0:
        return boxes, flags
    k_of = np.zeros(len(boxes), np.int64)
    if len(pred):
        home, claims = blob_claims(boxes, pred, cover)
        k_of = np.bincount(home[claims], minlength=len(boxes))
    wide_k = np.zeros(len(boxes), np.int64)
    if size_prior is not None and size_prior.ready:
        ratio = size_prior.ratio(boxes)
        r = ratio[:, 0]
        k = np.clip(np.round(r), 2, max_parts)
        # only blobs as tall as an object: a low wide blob is clutter, not people side by side
        wide_k = np.where((r >= wide) & (ratio[:, 1] >= tall), k, 0).astype(np.int64)
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
            parts = split_by_width(boxes[i], mask, int(wide_k[i]), valley)
        new.append(parts)
        new_flags.append(np.full(len(parts), SPLIT if len(parts) > 1 else flags[i], np.int8))
    return np.concatenate(new), np.concatenate(new_flags)
