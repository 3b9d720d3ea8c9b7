"""Pieces of one object's track: which later starts follow an ending, and whose piece is first.

Two stages join the pieces of a track that a tracker ended and started again: offline
relinking (:mod:`mvtrack.tracking.relink`) and the counting of movements
(:func:`mvtrack.analytics.movements.join_fragments`). Each tests its pairs its own way; both
find the candidate pairs and follow the chains ``a → b → c`` of the joined ones with the two
functions here.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

IntArray = NDArray[np.int64]


def starts_between(start: IntArray, first: IntArray, last: IntArray
                   ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Every pair ``(a, b)`` with ``first[a] <= start[b] <= last[a]``.

    ``start`` (T,) is each piece's first frame, ``first`` and ``last`` (T,) the window of
    frames in which a piece that continues ``a`` may start. The pairs are found by sorting
    the starts, so the cost follows the number of pairs, not the square of the pieces.
    Returns the indices ``a`` and ``b`` (P,), by ``a``, then by start.
    """
    start = np.asarray(start)
    by_start = np.argsort(start, kind="stable")
    starts = start[by_start]
    lo = np.searchsorted(starts, first, side="left")
    hi = np.searchsorted(starts, last, side="right")
    count = np.maximum(hi - lo, 0)
    a = np.repeat(np.arange(count.size), count)
    offset = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    return a.astype(np.intp), by_start[np.repeat(lo, count) + offset].astype(np.intp)


def chain_heads(parent: NDArray[np.intp]) -> NDArray[np.intp]:
    """The first piece of each piece's chain, where ``parent[b] = a`` says ``b`` continues
    ``a`` (``parent[a] = a`` for a first piece; the links must form no cycle)."""
    head = np.asarray(parent).copy()
    while True:
        nxt = head[head]
        if np.array_equal(nxt, head):
            return head
        head = nxt
