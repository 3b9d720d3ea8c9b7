"""Intersection over union of axis-aligned boxes: all pairs of two sets, or the overlapping
pairs of two whole sequences.

Every IoU in :mod:`mvtrack.eval` comes from one elementwise formula, the one of TrackEval's
``_calculate_box_ious`` and of MOTChallenge scoring scripts built on motmetrics: corners
``x₂ = left + width``, ``y₂ = top + height``, areas ``(x₂ - x₁)(y₂ - y₁)`` and the IoU
``inter / (area_a + area_b - inter)``, 0 where a box or the union has no area (≤ machine ε).
Computed pair by pair or as a matrix it gives the same bits, so a score computed here equals
one computed by those tools on the same files to the last digit.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from itertools import chain

import numpy as np
from numpy.typing import ArrayLike

from mvtrack.types import FloatArray, IntArray

_EPS = float(np.finfo(np.float64).eps)

#: Candidate pairs, and boxes of the grid search, handled at once (they bound the memory of
#: :func:`overlapping_pairs`).
_CHUNK_PAIRS = 1 << 20
_BLOCK_BOXES = 1 << 15


def _corners(tlwh: FloatArray) -> FloatArray:
    x1, y1 = tlwh[..., 0], tlwh[..., 1]
    return np.stack([x1, y1, x1 + tlwh[..., 2], y1 + tlwh[..., 3]], axis=-1)


def _iou(a: FloatArray, b: FloatArray) -> FloatArray:
    """IoU of corner boxes ``a`` and ``b`` (broadcast against each other)."""
    iw = np.maximum(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0.0)
    ih = np.maximum(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0.0)
    inter = iw * ih
    area_a = (a[..., 2] - a[..., 0]) * (a[..., 3] - a[..., 1])
    area_b = (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])
    union = area_a + area_b - inter
    ok = (area_a > _EPS) & (area_b > _EPS) & (union > _EPS)
    out = np.zeros(np.broadcast(inter, ok).shape)
    np.divide(inter, union, out=out, where=ok)
    return out


def iou_matrix(a_tlwh: ArrayLike, b_tlwh: ArrayLike) -> FloatArray:
    """IoU of every box in ``a`` with every box in ``b``.

    .. math:: \\mathrm{IoU}(a, b) = \\frac{|a \\cap b|}{|a| + |b| - |a \\cap b|}

    Parameters
    ----------
    a_tlwh : (N, 4) array
        Boxes ``(left, top, width, height)``.
    b_tlwh : (M, 4) array
        Boxes ``(left, top, width, height)``.

    Returns
    -------
    (N, M) float64
        IoU in [0, 1]; 0 where the boxes do not overlap or a box has no area.
    """
    a = _corners(np.asarray(a_tlwh, dtype=np.float64).reshape(-1, 4))
    b = _corners(np.asarray(b_tlwh, dtype=np.float64).reshape(-1, 4))
    return _iou(a[:, None, :], b[None, :, :])


@dataclass(frozen=True)
class BoxPairs:
    """The overlapping same-frame pairs of two box tables.

    Attributes
    ----------
    a, b : (P,) int64
        Row of each pair in table ``a`` and in table ``b``.
    iou : (P,) float64
        Their IoU, > 0.

    Pairs are sorted by frame, then by the file order of ``a`` within the frame, then by
    the file order of ``b``: the row and column order of a per-frame distance matrix.
    """

    a: IntArray
    b: IntArray
    iou: FloatArray

    def __len__(self) -> int:
        return int(self.a.shape[0])

    def take(self, idx: IntArray | np.ndarray) -> BoxPairs:
        """A subset of the pairs (order kept for a boolean mask or sorted indices)."""
        return BoxPairs(self.a[idx], self.b[idx], self.iou[idx])

    def frame_slices(self, frame_a: IntArray) -> list[tuple[int, int]]:
        """``(start, stop)`` of the pairs of each frame, given the frame of every row of ``a``."""
        if self.a.size == 0:
            return []
        cuts = (np.flatnonzero(np.diff(frame_a[self.a])) + 1).tolist()
        return list(zip([0, *cuts], [*cuts, self.a.size], strict=True))


def _chunks(count: IntArray) -> Iterator[IntArray]:
    """Groups of consecutive items whose counts add up to about ``_CHUNK_PAIRS`` each."""
    chunk_id = (np.cumsum(count) - count) // _CHUNK_PAIRS
    for part in np.split(np.arange(count.size), np.flatnonzero(np.diff(chunk_id)) + 1):
        if part.size:
            yield part


def _within(count: IntArray) -> IntArray:
    """``0 … count[i] - 1`` for each item ``i``, concatenated."""
    return np.arange(int(count.sum()), dtype=np.int64) - np.repeat(np.cumsum(count) - count, count)


def _same_frame_pairs(
    frame_a: IntArray, rows_a: IntArray, frame_b: IntArray, rows_b: IntArray
) -> Iterator[tuple[IntArray, IntArray]]:
    """Every same-frame pair of the rows ``rows_a`` of ``a`` and ``rows_b`` of ``b``, in chunks.

    ``rows_a`` and ``rows_b`` must be sorted by frame.
    """
    va, sa, na = np.unique(frame_a[rows_a], return_index=True, return_counts=True)
    vb, sb, nb = np.unique(frame_b[rows_b], return_index=True, return_counts=True)
    _, ia, ib = np.intersect1d(va, vb, assume_unique=True, return_indices=True)
    sa, na, sb, nb = sa[ia], na[ia], sb[ib], nb[ib]
    count = na * nb
    for f in _chunks(count):
        c = count[f]
        k, nb_r = _within(c), np.repeat(nb[f], c)
        yield rows_a[np.repeat(sa[f], c) + k // nb_r], rows_b[np.repeat(sb[f], c) + k % nb_r]


def _grid_pairs(
    rank_a: IntArray, ca: FloatArray, rank_b: IntArray, cb: FloatArray, cell: FloatArray
) -> Iterator[tuple[IntArray, IntArray]]:
    """Same-frame pairs of boxes whose centres lie in the same or adjacent grid cells.

    With cells at least as wide (high) as half the summed widths (heights) of any two of
    the boxes, two overlapping boxes always have their centres in adjacent cells, so this is
    a superset of the overlapping pairs. ``rank_*`` number the frames 0 … F-1. Yields the
    pairs in chunks (``a`` in blocks of ``_BLOCK_BOXES``), so memory stays bounded.
    """
    if ca.shape[0] == 0 or cb.shape[0] == 0:
        return
    ga = np.floor(0.5 * (ca[:, :2] + ca[:, 2:]) / cell).astype(np.int64)
    gb = np.floor(0.5 * (cb[:, :2] + cb[:, 2:]) / cell).astype(np.int64)
    lo = np.minimum(ga.min(axis=0), gb.min(axis=0)) - 1
    span = np.maximum(ga.max(axis=0), gb.max(axis=0)) - lo + 2  # cells per axis, padded
    n_frames = int(max(rank_a.max(), rank_b.max())) + 1
    if float(span[0]) * float(span[1]) * n_frames >= 2.0**62:
        yield from _grid_pairs(rank_a, ca, rank_b, cb, 2.0 * cell)  # coarser cells still cover
        return
    key_a = (rank_a * span[0] + ga[:, 0] - lo[0]) * span[1] + ga[:, 1] - lo[1]
    key_b = (rank_b * span[0] + gb[:, 0] - lo[0]) * span[1] + gb[:, 1] - lo[1]
    order_a, order_b = np.argsort(key_a), np.argsort(key_b)
    sorted_b = key_b[order_b]
    offsets = (np.array([-1, 0, 1])[:, None] * span[1] + np.array([-1, 0, 1])[None, :]).ravel()
    for block in np.array_split(order_a, -(-order_a.size // _BLOCK_BOXES)):
        # (9, n) neighbouring cells, each row sorted (searchsorted is fastest so).
        near = key_a[block][None, :] + offsets[:, None]
        start = np.searchsorted(sorted_b, near, side="left").ravel()
        count = np.searchsorted(sorted_b, near, side="right").ravel() - start
        owner = np.tile(block, offsets.size)
        for part in _chunks(count):
            c = count[part]
            yield np.repeat(owner[part], c), order_b[np.repeat(start[part], c) + _within(c)]


def overlapping_pairs(
    frame_a: ArrayLike, tlwh_a: ArrayLike, frame_b: ArrayLike, tlwh_b: ArrayLike
) -> BoxPairs:
    """All same-frame pairs of boxes of ``a`` and ``b`` with IoU > 0.

    Memory and time grow with the number of boxes and of overlapping pairs, not with the
    product of the box counts of a frame nor with the largest frame number: boxes up to twice
    the median size are paired through a grid of cells as large as the largest of them
    (vectorised over all frames at once), the few larger ones with every box of their frame.

    Parameters
    ----------
    frame_a, frame_b : (K,) int
        Frame of each box.
    tlwh_a, tlwh_b : (K, 4) float
        Boxes ``(left, top, width, height)``.

    Returns
    -------
    BoxPairs
        Sorted by frame, then by the input order of ``a`` within the frame, then of ``b``.
    """
    fa = np.asarray(frame_a, dtype=np.int64).reshape(-1)
    fb = np.asarray(frame_b, dtype=np.int64).reshape(-1)
    ta = np.asarray(tlwh_a, dtype=np.float64).reshape(-1, 4)
    tb = np.asarray(tlwh_b, dtype=np.float64).reshape(-1, 4)
    empty = np.zeros(0, np.int64)
    if fa.size == 0 or fb.size == 0:
        return BoxPairs(empty, empty, np.zeros(0))
    ca, cb = _corners(ta), _corners(tb)
    rank = np.unique(np.concatenate([fa, fb]), return_inverse=True)[1].reshape(-1)
    rank_a, rank_b = rank[: fa.size], rank[fa.size :]
    wh_a, wh_b = ca[:, 2:] - ca[:, :2], cb[:, 2:] - cb[:, :2]
    limit = 2.0 * np.median(np.concatenate([wh_a, wh_b]), axis=0)
    small_a, small_b = (wh_a <= limit).all(axis=1), (wh_b <= limit).all(axis=1)
    # Cells as large as the largest small box: overlapping centres are then adjacent.
    cell = np.concatenate([wh_a[small_a], wh_b[small_b], np.zeros((1, 2))]).max(axis=0)
    cell = np.maximum(cell, 1e-9 * np.maximum(np.abs(ca).max(), 1.0))
    ia, ib = np.flatnonzero(small_a), np.flatnonzero(small_b)
    big_a, big_b = np.flatnonzero(~small_a), np.flatnonzero(~small_b)
    candidates = chain(
        ((ia[i], ib[j]) for i, j in _grid_pairs(rank_a[ia], ca[ia], rank_b[ib], cb[ib], cell)),
        # Pairs with a large box: every box of the same frame (pairs of two large ones once).
        _same_frame_pairs(fa, big_a[np.argsort(fa[big_a], kind="stable")],
                          fb, np.argsort(fb, kind="stable")),
        _same_frame_pairs(fa, ia[np.argsort(fa[ia], kind="stable")],
                          fb, big_b[np.argsort(fb[big_b], kind="stable")]),
    )
    found = []
    for i, j in candidates:
        iou = _iou(ca[i], cb[j])
        hit = np.flatnonzero(iou > 0.0)
        found.append((i[hit], j[hit], iou[hit]))
    if not found:
        return BoxPairs(empty, empty, np.zeros(0))
    pa, pb, iou = (np.concatenate(parts) for parts in zip(*found, strict=True))
    # Frame-major order, then input order on each side: positions in a stable frame sort.
    pos_a = np.empty(fa.size, np.int64)
    pos_a[np.argsort(fa, kind="stable")] = np.arange(fa.size)
    order = np.lexsort((pb, pos_a[pa]))
    return BoxPairs(pa[order], pb[order], iou[order])
