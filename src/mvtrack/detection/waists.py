r"""Blobs that hold several objects cut at their waists; fragments of one object joined.

Two cars in adjacent lanes, or two people side by side, merge into one foreground blob; a car
whose windscreen matches the road falls apart into two. With the sizes the scene's kinds have
where a blob stands (:class:`~mvtrack.detection.kinds.KindModel`):

- :func:`cut_at_waists` — a blob at least ``over`` times as long as one object along an axis
  is cut where its *profile* (the count of its pixels in each column, or row) dips: the
  emptiest column at least ``min_part`` of an object from either end is a cut if its count
  is at most ``valley`` times the fuller of the two parts' peaks' lower one,

  .. math:: p(c^*) \le v\,\min\big(\max_{c < c^*} p(c),\; \max_{c > c^*} p(c)\big),

  and the parts are cut again while they are long enough. A bus, as long as two cars but
  without a waist, stays whole; two cars touching bumper to bumper at a narrow bridge of
  pixels are two.
- :func:`join_fragments` — blobs whose union is explained as one object of a kind better
  than either of them alone (:meth:`~mvtrack.detection.kinds.KindModel.match`) and which lie
  within a fraction of that object's size of each other are joined.

Boxes are ``(left, top, width, height)`` with pixel ``(col, row)`` covering
``[col - 0.5, col + 0.5)`` (the convention of :mod:`mvtrack.detection.blobs`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.kinds import KindModel

FloatArray = NDArray[np.float64]


def _cut(profile: NDArray[np.int64], lo: int, hi: int, valley: float) -> int:
    """The waist of ``profile`` in ``[lo, hi)``, or -1."""
    if hi <= lo:
        return -1
    c = lo + int(np.argmin(profile[lo:hi]))
    left = profile[:c].max(initial=0)
    right = profile[c + 1 :].max(initial=0)
    return c if profile[c] <= valley * min(left, right) else -1


def _profiles(m: NDArray[np.bool_], axis: int) -> tuple[NDArray[np.int64], ...]:
    """The count profile of a blob along ``axis`` (pixels per column, ``axis`` 0, or per
    row), and for columns also its upper envelope (the blob's height above its lowest row in
    each column): objects side by side on the ground dip between their tops even where their
    lower parts overlap."""
    counts = m.sum(axis=axis).astype(np.int64)
    if axis != 0:
        return (counts,)
    rows = m.shape[0]
    top = np.where(m.any(axis=0), m.argmax(axis=0), rows)
    return counts, (rows - top).astype(np.int64)


def cut_at_waists(
    labels: NDArray[np.integer], label: NDArray[np.intp], boxes: FloatArray,
    part: FloatArray, *, over: float = 1.5, min_part: float = 0.5, valley: float = 0.5,
    max_cuts: int = 6,
) -> tuple[FloatArray, NDArray[np.intp]]:
    """Cut each blob at its waists (module docstring).

    Parameters
    ----------
    labels : (H, W) int
        Label image of the blobs (``cv2.connectedComponents``).
    label : (M,) int
        Label of each blob to cut.
    boxes : (M, 4) float
        Their boxes.
    part : (M, 2) float
        The size ``(w, h)`` of one object where each blob stands.
    over, min_part, valley : float
        A part is cut along an axis when it is at least ``over`` objects long there, at a
        column (row) at least ``min_part`` of an object from its ends whose pixel count is at
        most ``valley`` times the lower of the two sides' peaks.
    max_cuts : int
        Most cuts of one blob.

    Returns
    -------
    boxes : (K, 4) float
        The parts' boxes (a blob that is not cut gives its own, tightened to its pixels).
    source : (K,) int
        Index of the blob each part comes from.
    """
    out: list[tuple[float, float, float, float]] = []
    src: list[int] = []
    for i in range(len(label)):  # the few blobs longer than one object
        x0, y0 = int(boxes[i, 0] + 0.5), int(boxes[i, 1] + 0.5)
        w, h = round(boxes[i, 2]), round(boxes[i, 3])
        sub = labels[y0 : y0 + h, x0 : x0 + w] == label[i]
        ew, eh = float(part[i, 0]), float(part[i, 1])
        todo = [(0, 0, w, h)]
        cuts = 0
        while todo:  # the parts of one blob (a handful)
            sx, sy, sw, sh = todo.pop()
            m = sub[sy : sy + sh, sx : sx + sw]
            cols = np.flatnonzero(m.any(axis=0))
            rows = np.flatnonzero(m.any(axis=1))
            if cols.size == 0:
                continue
            sx, sw = sx + int(cols[0]), int(cols[-1] - cols[0] + 1)
            sy, sh = sy + int(rows[0]), int(rows[-1] - rows[0] + 1)
            m = sub[sy : sy + sh, sx : sx + sw]
            best = None
            if cuts < max_cuts:
                for axis, length, size in ((0, sw, ew), (1, sh, eh)):
                    if length < over * size:
                        continue
                    margin = max(int(min_part * size), 1)
                    for profile in _profiles(m, axis):
                        c = _cut(profile, margin, length - margin, valley)
                        if c > 0:
                            depth = profile[c] / max(int(profile.max()), 1)
                            if best is None or depth < best[2]:
                                best = (axis, c, depth)
            if best is None:
                out.append((x0 + sx - 0.5, y0 + sy - 0.5, float(sw), float(sh)))
                src.append(i)
                continue
            cuts += 1
            axis, c, _ = best
            if axis == 0:
                todo += [(sx, sy, c, sh), (sx + c + 1, sy, sw - c - 1, sh)]
            else:
                todo += [(sx, sy, sw, c), (sx, sy + c + 1, sw, sh - c - 1)]
    return np.array(out, np.float64).reshape(-1, 4), np.array(src, np.intp)


def join_fragments(
    boxes: FloatArray, kinds: KindModel, *, gap: float = 0.4, gain: float = 1.0,
    max_z: float = 2.5,
) -> tuple[FloatArray, NDArray[np.intp]]:
    """Join blobs that are fragments of one object (module docstring).

    Two boxes are joined when they lie within ``gap`` of the object's size of each other
    (along each axis), their union is explained as one object of a kind with distance
    ``z ≤ max_z``, and that is at least ``gain`` better than the better of the two boxes
    alone. Joined pairs are grouped transitively; a group is joined whole if its union
    still fits one object.

    Returns
    -------
    boxes : (K, 4) float
        The joined boxes first, then the untouched ones.
    group : (M,) int
        For each input box, the output box it went into.
    """
    b = np.asarray(boxes, np.float64).reshape(-1, 4)
    m = len(b)
    ident = np.arange(m)
    if m < 2 or not kinds.ready:
        return b, ident
    lo, hi = b[:, :2], b[:, :2] + b[:, 2:]
    iu, ju = np.triu_indices(m, 1)
    # gap between the two boxes along each axis; only pairs closer than the larger of the
    # two along both axes can be fragments of one object
    gaps = np.maximum(np.maximum(lo[iu] - hi[ju], lo[ju] - hi[iu]), 0.0)
    close = (gaps <= np.maximum(b[iu, 2:], b[ju, 2:])).all(axis=1)
    iu, ju, gaps = iu[close], ju[close], gaps[close]
    if iu.size == 0:
        return b, ident
    ulo = np.minimum(lo[iu], lo[ju])
    pairs = np.concatenate([ulo, np.maximum(hi[iu], hi[ju]) - ulo], axis=1)
    kind_u, parts_u, z_u = kinds.match(pairs)
    one = (parts_u == 1).all(axis=1) & (z_u <= max_z)
    if not one.any():
        return b, ident
    size = kinds.expected(pairs)[np.arange(len(pairs)), np.maximum(kind_u, 0)]
    near = (gaps <= gap * size).all(axis=1)
    _, parts_b, z_b = kinds.match(b)
    alone = np.where((parts_b == 1).all(axis=1), z_b, np.inf)
    better = z_u + gain <= np.minimum(alone[iu], alone[ju])
    ok = one & near & better
    if not ok.any():
        return b, ident
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(int(ok.sum())), (iu[ok], ju[ok])), shape=(m, m))
    n, comp = connected_components(graph, directed=False)
    count = np.bincount(comp, minlength=n)
    glo = np.full((n, 2), np.inf)
    ghi = np.full((n, 2), -np.inf)
    np.minimum.at(glo, comp, lo)
    np.maximum.at(ghi, comp, hi)
    gbox = np.column_stack([glo, ghi - glo])
    _, gparts, gz = kinds.match(gbox)
    fits = (count >= 2) & (gparts == 1).all(axis=1) & (gz <= max_z)
    joined = fits[comp]
    new_index = np.full(n, -1)
    new_index[fits] = np.arange(int(fits.sum()))
    group = np.empty(m, np.intp)
    group[joined] = new_index[comp[joined]]
    rest = np.flatnonzero(~joined)
    group[rest] = int(fits.sum()) + np.arange(len(rest))
    return np.concatenate([gbox[fits], b[rest]]), group
