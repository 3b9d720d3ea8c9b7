"""The candidate pairs of a frame: the tracks and detections inside each other's gate.

:func:`quadratic_pairs` finds the pairs inside the quadratic gate of
:mod:`mvtrack.association.gate`,

.. math:: Δ^T S^{-1} Δ + w_s \\lVert \\ln(wh_d / wh_t) \\rVert^2 \\le g,

pair by pair in a small frame and through a grid of detection cells in a large one, so the
work grows with the pairs, not with ``N × M``; :func:`matrix_pairs` takes them from a cost
matrix (``iou``, ``coupled-literal``). Both are compiled kernels (:func:`mvtrack.jit.kernel`)
and give the pairs sorted by track, then detection.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = ["matrix_pairs", "quadratic_pairs"]

#: below this many track × detection tests a frame is gated pair by pair, above through a grid
_DENSE_TESTS = 4096


@kernel
def _pair_cost(i: int, j: int, cx: FloatArray, S: FloatArray, twh: FloatArray,
               dxy: FloatArray, dwh: FloatArray, size_w: float) -> float:
    """The gate's value of track ``i`` and detection ``j``.

    ``S`` (N, 3) is the gate's covariance ``[[s_xx, s_xy], [s_xy, s_yy]]`` as ``(s_xx, s_xy,
    s_yy)``; the value is ``Δᵀ S⁻¹ Δ`` plus ``size_w`` times the squared log ratios of the
    widths and heights.
    """
    sxx, sxy, syy = S[i, 0], S[i, 1], S[i, 2]
    det = sxx * syy - sxy * sxy
    dx, dy = dxy[j, 0] - cx[i, 0], dxy[j, 1] - cx[i, 1]
    d2 = (syy * dx * dx - 2.0 * sxy * dx * dy + sxx * dy * dy) / det  # Δᵀ S⁻¹ Δ
    if size_w > 0.0:
        lw = math.log(dwh[j, 0] / twh[i, 0])
        lh = math.log(dwh[j, 1] / twh[i, 1])
        d2 += size_w * (lw * lw + lh * lh)
    return d2


@kernel
def quadratic_pairs(cx: FloatArray, S: FloatArray, twh: FloatArray, tsel: NDArray[np.bool_],
                    dxy: FloatArray, dwh: FloatArray, dsel: NDArray[np.bool_], gate: float,
                    size_w: float) -> tuple[IntArray, IntArray, FloatArray]:
    """The pairs of selected tracks and detections inside the quadratic gate, with their
    values (:func:`_pair_cost`), sorted by track then detection.

    A track's gate reaches ``√(g s_xx)`` along x and ``√(g s_yy)`` along y. A small frame is
    tested pair by pair; a large one bins the detections into square cells of the median
    reach and tests each track against the cells its reach covers.
    """
    n, m = cx.shape[0], dxy.shape[0]
    tr = np.flatnonzero(tsel)
    dr = np.flatnonzero(dsel)
    cap = 16 + 4 * (tr.size + dr.size)
    ti = np.empty(cap, np.intp)
    dj = np.empty(cap, np.intp)
    cost = np.empty(cap, np.float64)
    k = 0
    if tr.size == 0 or dr.size == 0 or n == 0 or m == 0:
        return ti[:0], dj[:0], cost[:0]
    if tr.size * dr.size <= _DENSE_TESTS:
        for i in tr:
            rx, ry = math.sqrt(gate * S[i, 0]), math.sqrt(gate * S[i, 2])
            for j in dr:
                if abs(dxy[j, 0] - cx[i, 0]) > rx or abs(dxy[j, 1] - cx[i, 1]) > ry:
                    continue
                c = _pair_cost(i, j, cx, S, twh, dxy, dwh, size_w)
                if c <= gate:
                    if k == cap:
                        cap *= 2
                        ti, dj, cost = _grow(ti, dj, cost, cap)
                    ti[k], dj[k], cost[k] = i, j, c
                    k += 1
        return ti[:k], dj[:k], cost[:k]
    # the detections binned into square cells of the median reach (CSR: the members of cell
    # c are members[start[c]:start[c + 1]], cells numbered column by column)
    reach = np.empty(tr.size)
    for a in range(tr.size):
        i = tr[a]
        reach[a] = math.sqrt(gate * max(S[i, 0], S[i, 2]))
    cell = max(np.median(reach), 1.0)
    x0, x1 = dxy[dr, 0].min(), dxy[dr, 0].max()
    y0, y1 = dxy[dr, 1].min(), dxy[dr, 1].max()
    nx, ny = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    while nx * ny > 4 * dr.size + 16:  # no more cells than a few per detection
        cell *= 2.0
        nx, ny = int((x1 - x0) / cell) + 1, int((y1 - y0) / cell) + 1
    cid = np.empty(dr.size, np.int64)
    start = np.zeros(nx * ny + 1, np.int64)
    for b in range(dr.size):
        j = dr[b]
        c = int((dxy[j, 0] - x0) / cell) * ny + int((dxy[j, 1] - y0) / cell)
        cid[b] = c
        start[c + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(dr.size, np.intp)
    for b in range(dr.size):
        members[fill[cid[b]]] = dr[b]
        fill[cid[b]] += 1
    for a in range(tr.size):
        i = tr[a]
        rx, ry = math.sqrt(gate * S[i, 0]), math.sqrt(gate * S[i, 2])
        gx0 = max(math.floor((cx[i, 0] - rx - x0) / cell), 0)
        gx1 = min(math.floor((cx[i, 0] + rx - x0) / cell), nx - 1)
        gy0 = max(math.floor((cx[i, 1] - ry - y0) / cell), 0)
        gy1 = min(math.floor((cx[i, 1] + ry - y0) / cell), ny - 1)
        first = k
        for gx in range(gx0, gx1 + 1):
            if gy1 < gy0:
                break
            for p in range(start[gx * ny + gy0], start[gx * ny + gy1 + 1]):
                j = members[p]
                if abs(dxy[j, 0] - cx[i, 0]) > rx or abs(dxy[j, 1] - cx[i, 1]) > ry:
                    continue
                c = _pair_cost(i, j, cx, S, twh, dxy, dwh, size_w)
                if c <= gate:
                    if k == cap:
                        cap *= 2
                        ti, dj, cost = _grow(ti, dj, cost, cap)
                    ti[k], dj[k], cost[k] = i, j, c
                    # keep this track's pairs in detection order (insertion, a few at most)
                    e = k
                    while e > first and dj[e - 1] > dj[e]:
                        dj[e - 1], dj[e] = dj[e], dj[e - 1]
                        cost[e - 1], cost[e] = cost[e], cost[e - 1]
                        e -= 1
                    k += 1
    return ti[:k], dj[:k], cost[:k]


@kernel
def _grow(ti: IntArray, dj: IntArray, cost: FloatArray, cap: int
          ) -> tuple[IntArray, IntArray, FloatArray]:
    t2, d2, c2 = np.empty(cap, np.intp), np.empty(cap, np.intp), np.empty(cap, np.float64)
    k = ti.size
    t2[:k], d2[:k], c2[:k] = ti, dj, cost
    return t2, d2, c2


@kernel
def matrix_pairs(cost: FloatArray, tsel: NDArray[np.bool_], dsel: NDArray[np.bool_],
                 gate: float) -> tuple[IntArray, IntArray, FloatArray]:
    """The pairs of selected rows and columns of a cost matrix within ``gate``."""
    n, m = cost.shape
    k = 0
    ti = np.empty(n * m, np.intp)
    dj = np.empty(n * m, np.intp)
    c = np.empty(n * m, np.float64)
    for i in range(n):
        if not tsel[i]:
            continue
        for j in range(m):
            if dsel[j] and cost[i, j] <= gate:
                ti[k], dj[k], c[k] = i, j, cost[i, j]
                k += 1
    return ti[:k], dj[:k], c[:k]
