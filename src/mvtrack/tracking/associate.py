"""The tracker's fast association path: gating and global assignment for point distances.

For the distances whose gate is a disc around the prediction — ``euclidean`` (eq. (8) of
paper 2) and ``mahalanobis`` with an isotropic innovation covariance ``S = s I`` (what the
per-axis filters give, SPEC E2.3) — the tracker gates and assigns here with a small, fixed
number of array operations per frame. Everything else goes through
:mod:`mvtrack.association` (the same values; this module is tested against it).

Gating is dense (an ``N × M`` matrix by broadcasting) for small problems and spatial (a
KD-tree over detections, pairs within each track's radius) for large ones, so the number of
pairs and the cost grow near-linearly with ``N``.

The ``optimal`` rule is the gated global nearest neighbour of
:func:`mvtrack.association.assign` (maximum number of gated pairs, then minimum total
cost), solved in three tiers:

1. *stars* — components of the gate graph with one track or one detection (isolated pairs
   included; most of them in sparse scenes) are solved by a vectorised minimum;
2. the remaining *conflict* pairs, when few, by one ``linear_sum_assignment`` on their compact
   dense matrix (the components are independent, so one solve of their union is exact);
3. otherwise one ``linear_sum_assignment`` per connected component.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: up to this many track × detection pairs the gate is evaluated densely
DENSE_PAIRS = 20_000
#: up to this many track × detection pairs one dense assignment solves the whole frame
DENSE_LSA = 2_500
#: up to this many cells the conflict pairs are solved in one dense assignment
DENSE_CONFLICT = 40_000

_EMPTY = np.zeros(0, dtype=np.intp)


def gate_pairs(
    txy: FloatArray, dxy: FloatArray, scale: FloatArray | None, gate: float
) -> tuple[IntArray, IntArray, FloatArray]:
    """Gated pairs ``(ti, dj, cost)`` with ``cost = |z_j − x̄_i|² / scale_i <= gate``.

    ``scale`` is ``None`` for the Euclidean distance (eq. (8) of paper 2, cost in px²) and the
    innovation variance ``s_i`` (N,) for the Mahalanobis distance with ``S_i = s_i I``
    (cost χ²-distributed with 2 degrees of freedom). Pairs come sorted by track, then
    detection.
    """
    n, m = txy.shape[0], dxy.shape[0]
    if n == 0 or m == 0:
        return _EMPTY, _EMPTY, np.zeros(0)
    if n * m <= DENSE_PAIRS:
        dx = dxy[:, 0] - txy[:, 0, None]
        dy = dxy[:, 1] - txy[:, 1, None]
        cost = dx * dx + dy * dy  # eq. (8) of paper 2, squared
        if scale is not None:
            cost /= scale[:, None]  # Δᵀ S⁻¹ Δ with S = s I
        ti, dj = np.nonzero(cost <= gate)
        return ti, dj, cost[ti, dj]
    radius = np.sqrt(gate * scale) if scale is not None else np.full(n, np.sqrt(gate))
    ti, dj = _spatial_pairs(txy, dxy, radius)
    d = dxy[dj] - txy[ti]
    cost = np.einsum("pi,pi->p", d, d)
    if scale is not None:
        cost /= scale[ti]
    keep = cost <= gate
    return ti[keep], dj[keep], cost[keep]


def dense_optimal(
    txy: FloatArray, dxy: FloatArray, scale: FloatArray | None, gate: float
) -> tuple[IntArray, IntArray]:
    """Gate and solve a small problem in one dense ``linear_sum_assignment``.

    Same result as :func:`gate_pairs` followed by :func:`optimal`: forbidden cells cost more
    than any set of gated pairs together, so the solver first maximises the number of gated
    pairs, then minimises their cost. Returns matched (track, detection) rows, by track.
    """
    dx = dxy[:, 0] - txy[:, 0, None]
    dy = dxy[:, 1] - txy[:, 1, None]
    cost = dx * dx + dy * dy  # eq. (8) of paper 2, squared
    if scale is not None:
        cost /= scale[:, None]  # Δᵀ S⁻¹ Δ with S = s I
    big = 2.0 * gate * (min(cost.shape) + 1) + 1.0
    cost[~(cost <= gate)] = big  # NaN never passes
    rows, cols = linear_sum_assignment(cost)
    keep = cost[rows, cols] < big
    return rows[keep], cols[keep]


def _spatial_pairs(txy: FloatArray, dxy: FloatArray, radius: FloatArray) -> tuple[IntArray, ...]:
    """Pairs with ``|d − t| <= radius_t`` via KD-trees, sorted by track then detection.

    Tracks within twice the median radius share one tree-against-tree query; the few with a
    wider gate (long coasting) are queried ball by ball, so they do not widen everyone's.
    """
    dtree = cKDTree(dxy)
    ref = 2.0 * float(np.median(radius))
    common = radius <= ref
    parts_t, parts_d = [], []
    idx = np.flatnonzero(common)
    if idx.size:
        ttree = cKDTree(txy[idx])
        sdm = ttree.sparse_distance_matrix(dtree, float(radius[idx].max()), p=2.0,
                                           output_type="ndarray")
        parts_t.append(idx[sdm["i"]])
        parts_d.append(sdm["j"].astype(np.intp))
    wide = np.flatnonzero(~common)
    if wide.size:
        balls = dtree.query_ball_point(txy[wide], radius[wide])
        counts = np.fromiter((len(b) for b in balls), dtype=np.intp, count=wide.size)
        parts_t.append(np.repeat(wide, counts))
        parts_d.append(np.fromiter((j for b in balls for j in b), dtype=np.intp,
                                   count=int(counts.sum())))
    ti = np.concatenate(parts_t) if len(parts_t) > 1 else parts_t[0]
    dj = np.concatenate(parts_d) if len(parts_d) > 1 else parts_d[0]
    order = np.lexsort((dj, ti))
    return ti[order], dj[order]


def _first_of_runs(key: IntArray) -> NDArray[np.bool_]:
    first = np.ones(key.shape[0], dtype=bool)
    first[1:] = key[1:] != key[:-1]
    return first


def _min_per(key: IntArray, cost: FloatArray, other: IntArray, sel: IntArray) -> IntArray:
    """Among pairs ``sel``, the cheapest per value of ``key`` (ties: lowest ``other``)."""
    order = sel[np.lexsort((other[sel], cost[sel], key[sel]))]
    return order[_first_of_runs(key[order])]


def optimal(
    ti: IntArray, dj: IntArray, cost: FloatArray, n: int, m: int
) -> tuple[IntArray, IntArray]:
    """Gated global nearest neighbour: matched (track, detection) rows, sorted by track.

    Maximises the number of matched gated pairs, then minimises their total cost (the default
    ``optimal`` rule of :func:`mvtrack.association.assign`).
    """
    p = ti.shape[0]
    if p == 0:
        return _EMPTY, _EMPTY
    deg_t = np.bincount(ti, minlength=n)
    deg_d = np.bincount(dj, minlength=m)
    # a track all of whose detections are its alone is the centre of a star component
    shared_d = deg_d[dj] > 1
    t_conf = np.bincount(ti, weights=shared_d, minlength=n) > 0
    shared_t = deg_t[ti] > 1
    d_conf = np.bincount(dj, weights=shared_t, minlength=m) > 0
    t_star = ~t_conf[ti]  # pairs of components with one track (or 1-1)
    d_star = ~d_conf[dj] & ~t_star  # components with one detection and several tracks
    parts = []
    sel = np.flatnonzero(t_star)
    if sel.size:
        parts.append(_min_per(ti, cost, dj, sel))
    sel = np.flatnonzero(d_star)
    if sel.size:
        parts.append(_min_per(dj, cost, ti, sel))
    hard = np.flatnonzero(~t_star & ~d_star)
    if hard.size:
        parts.append(_solve_conflicts(ti, dj, cost, hard))
    chosen = np.concatenate(parts) if len(parts) > 1 else parts[0]
    chosen = chosen[np.argsort(ti[chosen], kind="stable")]
    return ti[chosen], dj[chosen]


def _dense_lsa(t: IntArray, d: IntArray, c: FloatArray) -> IntArray:
    """Positions (into ``t``) of the pairs chosen by one gated dense assignment."""
    ut, lt = np.unique(t, return_inverse=True)
    ud, ld = np.unique(d, return_inverse=True)
    big = 2.0 * float(np.abs(c).sum()) + 1.0  # a forbidden cell costs more than all pairs
    a = np.full((ut.size, ud.size), big)
    a[lt, ld] = c
    rows, cols = linear_sum_assignment(a)
    pos = np.full((ut.size, ud.size), -1, dtype=np.intp)
    pos[lt, ld] = np.arange(t.size)
    got = pos[rows, cols]
    return got[got >= 0]


def _solve_conflicts(ti: IntArray, dj: IntArray, cost: FloatArray, hard: IntArray) -> IntArray:
    t, d, c = ti[hard], dj[hard], cost[hard]
    nt = np.unique(t).size
    nd = np.unique(d).size
    if nt * nd <= DENSE_CONFLICT:
        return hard[_dense_lsa(t, d, c)]
    # one assignment per connected component of the conflict graph
    _, lt = np.unique(t, return_inverse=True)
    _, ld = np.unique(d, return_inverse=True)
    g = coo_array((np.ones(t.size), (lt, nt + ld)), shape=(nt + nd, nt + nd))
    _, labels = connected_components(g, directed=False)
    lab = labels[lt]
    order = np.argsort(lab, kind="stable")
    bounds = np.flatnonzero(_first_of_runs(lab[order]))
    out = []
    for s, e in zip(bounds, [*bounds[1:], order.size], strict=True):
        idx = order[s:e]
        out.append(idx[_dense_lsa(t[idx], d[idx], c[idx])])
    return hard[np.concatenate(out)]
