"""The candidate pairs of a frame: the tracks and detections inside each other's gate.

:func:`quadratic_pairs` finds the pairs inside the quadratic gate of
:mod:`mvtrack.association.gate`,

.. math:: Δ^T S^{-1} Δ + w_s \\lVert \\ln(wh_d / wh_t) \\rVert^2 \\le g,

pair by pair in a small frame and through a grid of detection cells in a large one, so the
work grows with the pairs, not with ``N × M``. :func:`overlap_pairs` finds the pairs of the
``iou`` gate,

.. math:: 1 - \\mathrm{IoU}(b_t, b_d) + w_s \\lVert \\ln(wh_d / wh_t) \\rVert^2 \\le g,

the same way: below ``g = 1`` a pair passes only if its boxes overlap, so only the detections
whose boxes share a grid cell with the track's box are candidates. :func:`matrix_pairs` takes
them from a cost matrix (``coupled-literal``, not a region about the prediction). All are
compiled kernels (:func:`mvtrack.jit.kernel`) and give the pairs sorted by track, then
detection; :func:`frame_pairs` calls the one a gate names (:data:`BY_QUADRATIC`,
:data:`BY_OVERLAP`, :data:`BY_MATRIX`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = [
    "BY_MATRIX",
    "BY_OVERLAP",
    "BY_QUADRATIC",
    "frame_pairs",
    "matrix_pairs",
    "overlap_pairs",
    "quadratic_pairs",
]

#: how a gate's pairs are found (:func:`frame_pairs`): a quadratic form about the prediction,
#: box overlap (``iou``), a dense cost matrix
BY_QUADRATIC, BY_OVERLAP, BY_MATRIX = 0, 1, 2

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
    tr, dr, ti, dj, cost = _selected(tsel, dsel)
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
                    if k == ti.size:
                        ti, dj, cost = _grow(ti, dj, cost)
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
                    if k == ti.size:
                        ti, dj, cost = _grow(ti, dj, cost)
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
def _selected(tsel: NDArray[np.bool_], dsel: NDArray[np.bool_]
              ) -> tuple[IntArray, IntArray, IntArray, IntArray, FloatArray]:
    """The selected tracks and detections, and empty track, detection and value arrays for
    their pairs: room for a few pairs a row, more made by :func:`_grow`."""
    tr = np.flatnonzero(tsel)
    dr = np.flatnonzero(dsel)
    cap = 16 + 4 * (tr.size + dr.size)
    return tr, dr, np.empty(cap, np.intp), np.empty(cap, np.intp), np.empty(cap, np.float64)


@kernel
def _grow(ti: IntArray, dj: IntArray, cost: FloatArray
          ) -> tuple[IntArray, IntArray, FloatArray]:
    """Copies of the full pair arrays twice as long."""
    k = ti.size
    t2, d2, c2 = np.empty(2 * k, np.intp), np.empty(2 * k, np.intp), np.empty(2 * k, np.float64)
    t2[:k], d2[:k], c2[:k] = ti, dj, cost
    return t2, d2, c2


@kernel
def _overlap_cost(i: int, j: int, cx: FloatArray, twh: FloatArray, dxy: FloatArray,
                  dwh: FloatArray, size_w: float) -> float:
    """``1 − IoU`` of track ``i``'s box (centre ``cx[i]``, size ``twh[i]``) and detection
    ``j``'s, plus ``size_w`` times the squared log ratios of the widths and heights.

    The operations of :func:`mvtrack.association.distances.iou_cost` in the same order, so
    the same value to the last bit (the size term's logarithm to rounding).
    """
    w1, h1, w2, h2 = twh[i, 0], twh[i, 1], dwh[j, 0], dwh[j, 1]
    x1, y1, x2, y2 = cx[i, 0], cx[i, 1], dxy[j, 0], dxy[j, 1]
    iou = 0.0  # a NaN coordinate: no overlap (NumPy's NaN union is not > 0)
    if not (math.isnan(x1 + w1 + x2 + w2) or math.isnan(y1 + h1 + y2 + h2)):
        ix = min(x1 + w1 / 2, x2 + w2 / 2) - max(x1 - w1 / 2, x2 - w2 / 2)
        iy = min(y1 + h1 / 2, y2 + h2 / 2) - max(y1 - h1 / 2, y2 - h2 / 2)
        inter = max(ix, 0.0) * max(iy, 0.0)  # the overlap's area
        union = w1 * h1 + w2 * h2 - inter
        if union > 0.0:
            iou = inter / union
    value = 1.0 - min(max(iou, 0.0), 1.0)
    if size_w > 0.0:
        lw = _log_ratio(w2, w1)
        lh = _log_ratio(h2, h1)
        value = value + size_w * (lw * lw + lh * lh)
    return value


@kernel
def _log_ratio(a: float, b: float) -> float:
    """``ln(a / b)``, and where a box has no size what NumPy gives (±inf, NaN), not an
    error."""
    if b == 0.0:
        r = math.inf if a > 0.0 else (-math.inf if a < 0.0 else math.nan)
    else:
        r = a / b
    if 0.0 < r < math.inf:
        return math.log(r)
    if r == 0.0:
        return -math.inf
    return math.inf if r == math.inf else math.nan


@kernel
def _cells(lo: float, hi: float, origin: float, cell: float, count: int) -> tuple[int, int]:
    """The first and last of ``count`` cells of width ``cell`` from ``origin`` that the
    interval ``[lo, hi]`` touches (first > last: none)."""
    a = math.floor((lo - origin) / cell)
    b = math.floor((hi - origin) / cell)
    return max(a, 0), min(b, count - 1)


@kernel
def overlap_pairs(cx: FloatArray, twh: FloatArray, tsel: NDArray[np.bool_], dxy: FloatArray,
                  dwh: FloatArray, dsel: NDArray[np.bool_], gate: float, size_w: float
                  ) -> tuple[IntArray, IntArray, FloatArray]:
    """The pairs of selected tracks and detections within the ``iou`` gate, with their values
    (:func:`_overlap_cost`), sorted by track then detection.

    Boxes are centred on ``cx`` (N, 2) and ``dxy`` (M, 2) with sizes ``twh`` and ``dwh``.
    Below ``gate = 1`` a pair passes only if its boxes overlap (else ``1 − IoU = 1``), so a
    large frame puts each detection's box into the cells it covers of a grid of rectangles
    the size of the median detection box, and each track's box takes the detections of the
    cells it covers: two boxes that overlap share the cell of a point of their overlap. The
    value is then computed for those candidates only. A small frame, or ``gate >= 1`` (any
    pair may pass), is tested pair by pair.
    """
    n, m = cx.shape[0], dxy.shape[0]
    tr, dr, ti, dj, cost = _selected(tsel, dsel)
    k = 0
    if tr.size == 0 or dr.size == 0 or n == 0 or m == 0:
        return ti[:0], dj[:0], cost[:0]
    if gate >= 1.0 or tr.size * dr.size <= _DENSE_TESTS:
        for i in tr:
            for j in dr:
                c = _overlap_cost(i, j, cx, twh, dxy, dwh, size_w)
                if c <= gate:
                    if k == ti.size:
                        ti, dj, cost = _grow(ti, dj, cost)
                    ti[k], dj[k], cost[k] = i, j, c
                    k += 1
        return ti[:k], dj[:k], cost[:k]
    # the detections' boxes (a box with a coordinate that is not finite overlaps nothing:
    # its value is NaN or 1)
    box = np.empty((dr.size, 4))  # left, right, top, bottom
    keep = np.empty(dr.size, np.intp)
    ws = np.empty(dr.size)
    hs = np.empty(dr.size)
    nb = 0
    x0, x1, y0, y1 = math.inf, -math.inf, math.inf, -math.inf
    for b in range(dr.size):
        j = dr[b]
        w, h = dwh[j, 0], dwh[j, 1]
        left, right = dxy[j, 0] - w / 2, dxy[j, 0] + w / 2  # as in _overlap_cost
        top, bottom = dxy[j, 1] - h / 2, dxy[j, 1] + h / 2
        if not (math.isfinite(left) and math.isfinite(right) and math.isfinite(top)
                and math.isfinite(bottom)):
            continue
        box[nb, 0], box[nb, 1], box[nb, 2], box[nb, 3] = left, right, top, bottom
        keep[nb], ws[nb], hs[nb] = j, w, h
        nb += 1
        x0, x1 = min(x0, left), max(x1, right)
        y0, y1 = min(y0, top), max(y1, bottom)
    if nb == 0:
        return ti[:0], dj[:0], cost[:0]
    # cells the size of the median box, no more than a few per detection
    budget = 4 * nb + 16
    cw = max(np.median(ws[:nb]), (x1 - x0) / budget, 1e-9)
    ch = max(np.median(hs[:nb]), (y1 - y0) / budget, 1e-9)
    nx, ny = int((x1 - x0) / cw) + 1, int((y1 - y0) / ch) + 1
    while nx * ny > budget:
        cw *= 2.0
        ch *= 2.0
        nx, ny = int((x1 - x0) / cw) + 1, int((y1 - y0) / ch) + 1
    # each detection in every cell its box covers (CSR: the members of cell c are
    # members[start[c]:start[c + 1]], cells numbered column by column)
    start = np.zeros(nx * ny + 1, np.int64)
    for b in range(nb):
        gx0, gx1 = _cells(box[b, 0], box[b, 1], x0, cw, nx)
        gy0, gy1 = _cells(box[b, 2], box[b, 3], y0, ch, ny)
        for gx in range(gx0, gx1 + 1):
            for gy in range(gy0, gy1 + 1):
                start[gx * ny + gy + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    members = np.empty(start[nx * ny], np.intp)
    for b in range(nb):
        gx0, gx1 = _cells(box[b, 0], box[b, 1], x0, cw, nx)
        gy0, gy1 = _cells(box[b, 2], box[b, 3], y0, ch, ny)
        for gx in range(gx0, gx1 + 1):
            for gy in range(gy0, gy1 + 1):
                members[fill[gx * ny + gy]] = keep[b]
                fill[gx * ny + gy] += 1
    seen = np.full(m, -1, np.intp)  # the last track that took each detection as a candidate
    found = np.empty(nb, np.intp)
    for i in tr:
        w, h = twh[i, 0], twh[i, 1]
        left, right = cx[i, 0] - w / 2, cx[i, 0] + w / 2  # as in _overlap_cost
        top, bottom = cx[i, 1] - h / 2, cx[i, 1] + h / 2
        if not (math.isfinite(left) and math.isfinite(right) and math.isfinite(top)
                and math.isfinite(bottom)):
            continue
        gx0, gx1 = _cells(left, right, x0, cw, nx)
        gy0, gy1 = _cells(top, bottom, y0, ch, ny)
        f = 0
        for gx in range(gx0, gx1 + 1):
            if gy1 < gy0:
                break
            for p in range(start[gx * ny + gy0], start[gx * ny + gy1 + 1]):
                j = members[p]
                if seen[j] != i:
                    seen[j] = i
                    found[f] = j
                    f += 1
        if f == 0:
            continue
        cand = np.sort(found[:f])  # this track's pairs in detection order
        for e in range(f):
            j = cand[e]
            c = _overlap_cost(i, j, cx, twh, dxy, dwh, size_w)
            if c <= gate:
                if k == ti.size:
                    ti, dj, cost = _grow(ti, dj, cost)
                ti[k], dj[k], cost[k] = i, j, c
                k += 1
    return ti[:k], dj[:k], cost[:k]


@kernel
def frame_pairs(search: int, cx: FloatArray, S: FloatArray, cost: FloatArray,
                twh: FloatArray, tsel: NDArray[np.bool_], dxy: FloatArray, dwh: FloatArray,
                dsel: NDArray[np.bool_], gate: float, size_w: float
                ) -> tuple[IntArray, IntArray, FloatArray]:
    """The pairs of selected tracks and detections inside a gate, found as ``search`` says:
    :data:`BY_QUADRATIC` (centres ``cx``, covariances ``S``, :func:`quadratic_pairs`),
    :data:`BY_OVERLAP` (boxes, :func:`overlap_pairs`) or :data:`BY_MATRIX` (the values in
    ``cost`` (N, M), :func:`matrix_pairs`)."""
    if search == BY_MATRIX:
        return matrix_pairs(cost, tsel, dsel, gate)
    if search == BY_OVERLAP:
        return overlap_pairs(cx, twh, tsel, dxy, dwh, dsel, gate, size_w)
    return quadratic_pairs(cx, S, twh, tsel, dxy, dwh, dsel, gate, size_w)


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
