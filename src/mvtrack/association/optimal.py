"""The optimal assignment rule: global minimum-cost exclusive matching of gated pairs.

Solved per connected component of the gate graph so the cost grows with cluster size, not
N × M: leaves that cannot do better are matched exactly first (:func:`_peel_leaves`), stars
take their cheapest pair, 2 × 2 conflicts are solved in closed form, and the remaining
clusters go to ``scipy.optimize.linear_sum_assignment`` (dense) or to the sparse LAPJVsp of
``scipy.sparse.csgraph.min_weight_full_bipartite_matching`` (:func:`solve_sparse`). The
objective (cost of non-assignment ``u``) is described in :mod:`mvtrack.association.assign`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_array, csr_array
from scipy.sparse.csgraph import connected_components, min_weight_full_bipartite_matching

from mvtrack.association.order import best_of, first_per_group, rank_pairs

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = ["DENSE_FRAME_NODES", "SMALL_NODES", "SPARSE_CLUSTERS", "solve_optimal", "solve_sparse"]

#: with solver="auto", more conflicting clusters than this are solved in one sparse problem
SPARSE_CLUSTERS = 8
#: with solver="auto", clusters of at most this many tracks + detections are solved with a
#: dense ``linear_sum_assignment``; larger ones with the sparse solver
SMALL_NODES = 64
#: with solver="auto", a frame with at most this many gated tracks + detections is solved as
#: one dense problem without looking for clusters
DENSE_FRAME_NODES = 128
#: rounds of label propagation before falling back to SciPy's connected_components
_PROPAGATION_ROUNDS = 12
#: rounds of exact leaf peeling before the remaining clusters go to the solvers
_PEEL_ROUNDS = 8


def _peel_leaves(
    ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int, n_dets: int
) -> tuple[NDArray[np.bool_], IntArray]:
    """Exact reduction of the optimal problem: match leaves that cannot do better.

    If a detection's only gated track is ``t`` and it is ``t``'s cheapest detection, some
    optimal matching contains that pair (swap ``t``'s partner in any optimum for it: the cost
    does not rise, and an unmatched ``t`` only gains since every pair costs less than ``u``);
    likewise with tracks and detections exchanged. Accepted pairs never share a node, so a
    whole round is accepted at once; removing their nodes leaves a smaller problem whose
    optimum completes an optimum of the original. Returns the chosen mask and the rows of the
    pairs still alive after at most :data:`_PEEL_ROUNDS` rounds.
    """
    rank = rank_pairs(ti, dj, cost)
    chosen = np.zeros(ti.shape[0], dtype=bool)
    alive = np.arange(ti.shape[0])
    for _ in range(_PEEL_ROUNDS):
        t, d, r = ti[alive], dj[alive], rank[alive]
        deg_t = np.bincount(t, minlength=n_tracks)
        deg_d = np.bincount(d, minlength=n_dets)
        acc = ((deg_d[d] == 1) & (best_of(t, r, n_tracks)[t] == r)) | (
            (deg_t[t] == 1) & (best_of(d, r, n_dets)[d] == r)
        )
        if not acc.any():
            break
        chosen[alive[acc]] = True
        used_t = np.zeros(n_tracks, dtype=bool)
        used_t[t[acc]] = True
        used_d = np.zeros(n_dets, dtype=bool)
        used_d[d[acc]] = True
        alive = alive[~(used_t[t] | used_d[d])]
        if alive.size == 0:
            break
    return chosen, alive


def _solve_dense(t: IntArray, d: IntArray, c: FloatArray, half_u: float) -> NDArray[np.bool_]:
    """Optimal exclusive matching of one cluster; True for the chosen pairs.

    The augmented square matrix [[C, diag(u/2)], [diag(u/2), Cᵀ-pattern 0]] lets every node stay
    unmatched at cost u/2 (Jonker–Volgenant augmentation); forbidden entries are ``inf``.
    """
    ut, lt = np.unique(t, return_inverse=True)
    ud, ld = np.unique(d, return_inverse=True)
    nt, nd = ut.size, ud.size
    size = nt + nd
    a = np.full((size, size), np.inf)
    a[lt, ld] = c
    a[np.arange(nt), nd + np.arange(nt)] = half_u  # track left unmatched
    a[nt + np.arange(nd), np.arange(nd)] = half_u  # detection left unmatched
    a[nt:, nd:] = 0.0  # dummy to dummy
    rows, cols = linear_sum_assignment(a)
    real = (rows < nt) & (cols < nd)
    pos = np.full((nt, nd), -1, dtype=np.intp)
    pos[lt, ld] = np.arange(t.shape[0])
    chosen = np.zeros(t.shape[0], dtype=bool)
    chosen[pos[rows[real], cols[real]]] = True
    return chosen


def solve_sparse(
    t: IntArray, d: IntArray, c: FloatArray, half_u: float,
    ranks: tuple[int, IntArray, int, IntArray] | None = None,
) -> NDArray[np.bool_]:
    """Optimal exclusive matching of any number of clusters in one sparse LAPJVsp solve.

    Rows: tracks, then one dummy per detection; columns: detections, then one dummy per track.
    Edges: real pairs (cost), track → own dummy (u/2), detection dummy → detection (u/2), and
    the transposed pattern between dummies (0) so a perfect matching always exists. A constant
    offset keeps every weight non-zero (it adds the same amount to every perfect matching).
    ``ranks = (nt, lt, nd, ld)``, optional: the numbers of distinct tracks and detections and
    each pair's ranks among them, when the caller has them (``np.unique`` otherwise).
    """
    if ranks is None:
        ut, lt = np.unique(t, return_inverse=True)
        ud, ld = np.unique(d, return_inverse=True)
        nt, nd = ut.size, ud.size
    else:
        nt, lt, nd, ld = ranks
    p = t.shape[0]
    off = 1.0 + max(0.0, -float(c.min()))
    at = np.arange(nt)
    ad = np.arange(nd)
    rows = np.concatenate([lt, at, nt + ad, nt + ld])
    cols = np.concatenate([ld, nd + at, ad, nd + lt])
    w = np.concatenate(
        [c + off, np.full(nt, half_u + off), np.full(nd, half_u + off), np.full(p, off)]
    )
    g = csr_array((w, (rows, cols)), shape=(nt + nd, nd + nt))
    r, k = min_weight_full_bipartite_matching(g)
    real = (r < nt) & (k < nd)
    key = lt.astype(np.int64) * nd + ld
    order = np.argsort(key)
    hit = np.searchsorted(key[order], r[real].astype(np.int64) * nd + k[real])
    chosen = np.zeros(p, dtype=bool)
    chosen[order[hit]] = True
    return chosen


def _solve_2x2(
    t: IntArray, d: IntArray, c: FloatArray, lab: IntArray, u: float
) -> NDArray[np.bool_]:
    """Optimal matching of many clusters of exactly two tracks and two detections at once.

    Each cluster's 2 × 2 weight matrix w = u − cost (−∞ where there is no pair) is scored for
    the seven matchings (empty, four single pairs, two full ones); the best per cluster is
    kept. Ties go to the first in the order: diagonal, anti-diagonal, single pairs.
    """
    ulab, cl = np.unique(lab, return_inverse=True)
    k = ulab.size
    big = np.iinfo(np.intp).max
    tmin = np.full(k, big)
    np.minimum.at(tmin, cl, t)
    dmin = np.full(k, big)
    np.minimum.at(dmin, cl, d)
    tl = (t != tmin[cl]).astype(np.intp)  # local row 0 / 1 (lower / higher track row)
    dl = (d != dmin[cl]).astype(np.intp)
    w = np.full((k, 2, 2), -np.inf)
    w[cl, tl, dl] = u - c
    pos = np.full((k, 2, 2), -1, dtype=np.intp)
    pos[cl, tl, dl] = np.arange(t.shape[0])
    options = np.stack(
        [
            w[:, 0, 0] + w[:, 1, 1],
            w[:, 0, 1] + w[:, 1, 0],
            w[:, 0, 0],
            w[:, 0, 1],
            w[:, 1, 0],
            w[:, 1, 1],
            np.zeros(k),
        ],
        axis=1,
    )
    best = np.argmax(options, axis=1)  # first maximum wins
    picks = np.array(
        [
            [(0, 0), (1, 1)],
            [(0, 1), (1, 0)],
            [(0, 0), (0, 0)],
            [(0, 1), (0, 1)],
            [(1, 0), (1, 0)],
            [(1, 1), (1, 1)],
            [(-1, -1), (-1, -1)],
        ]
    )[best]  # (k, 2, 2): the (row, col) of up to two chosen pairs
    chosen = np.zeros(t.shape[0], dtype=bool)
    valid = picks[:, :, 0] >= 0
    rows = np.repeat(np.arange(k), 2).reshape(k, 2)
    p = pos[rows[valid], picks[:, :, 0][valid], picks[:, :, 1][valid]]
    chosen[p[p >= 0]] = True
    return chosen


def _components(ti: IntArray, dj: IntArray, n_tracks: int, n_dets: int) -> IntArray:
    """Connected-component label of every node (tracks, then detections) of the gate graph.

    Each label is the smallest node index in the component. Minimum-label propagation along
    the pairs with pointer jumping converges in a few rounds for the small clusters of
    typical frames; if it has not after :data:`_PROPAGATION_ROUNDS`, SciPy's
    ``connected_components`` finishes the job (large, long clusters).
    """
    nodes = n_tracks + n_dets
    a, b = ti, n_tracks + dj
    lab = np.arange(nodes)
    for _ in range(_PROPAGATION_ROUNDS):
        low = np.minimum(lab[a], lab[b])
        new = lab.copy()
        np.minimum.at(new, a, low)
        np.minimum.at(new, b, low)
        new = new[new[new]]  # pointer jumping
        if np.array_equal(new, lab):
            return lab
        lab = new
    graph = coo_array((np.ones(a.shape[0]), (a, b)), shape=(nodes, nodes))
    _, comp = connected_components(graph, directed=False)
    first = np.full(int(comp.max()) + 1, nodes)
    np.minimum.at(first, comp, np.arange(nodes))
    return first[comp]


def solve_optimal(
    ti: IntArray,
    dj: IntArray,
    cost: FloatArray,
    n_tracks: int,
    n_dets: int,
    unmatched_cost: float | None,
    solver: str,
) -> tuple[IntArray, ...]:
    if unmatched_cost is None:  # every pair worth matching alone; see the module docstring
        u = 2.0 * float(np.abs(cost).max()) * (1.0 + 1e-9) + 1e-12
    else:
        u = float(unmatched_cost)
    useful = cost < u  # a pair costing u or more never improves a matching
    if not useful.all():
        ti, dj, cost = ti[useful], dj[useful], cost[useful]
    if ti.size == 0:
        return ti, dj, cost
    deg_t = np.bincount(ti, minlength=n_tracks)
    deg_d = np.bincount(dj, minlength=n_dets)
    if deg_t.max() <= 1 and deg_d.max() <= 1:  # no conflicts at all: every pair stands alone
        return ti, dj, cost
    if (
        solver != "sparse"
        and np.count_nonzero(deg_t) + np.count_nonzero(deg_d) <= DENSE_FRAME_NODES
    ):
        chosen = _solve_dense(ti, dj, cost, u / 2)  # small frame: one dense solve, no clusters
        return ti[chosen], dj[chosen], cost[chosen]
    chosen, rest = _peel_leaves(ti, dj, cost, n_tracks, n_dets)
    if rest.size:
        t, d, c = ti[rest], dj[rest], cost[rest]
        labels = _components(t, d, n_tracks, n_dets)
        lab = labels[t]
        has_t = np.zeros(n_tracks, dtype=bool)
        has_t[t] = True
        has_d = np.zeros(n_dets, dtype=bool)
        has_d[d] = True
        ncomp = n_tracks + n_dets  # labels are node indices (not compact)
        nt = np.bincount(labels[:n_tracks][has_t], minlength=ncomp)
        nd = np.bincount(labels[n_tracks:][has_d], minlength=ncomp)
        trivial = (nt <= 1) | (nd <= 1)  # a star: every matching has at most one pair
        # stars left by the peeling (ties), all at once: the cheapest pair
        tri = np.flatnonzero(trivial[lab])
        if tri.size:
            order = tri[np.lexsort((d[tri], t[tri], c[tri], lab[tri]))]
            chosen[rest[order[first_per_group(lab[order])]]] = True
        # conflicting clusters (at least two tracks and two detections)
        hard = np.flatnonzero(~trivial[lab])
        if hard.size:
            hard_c = np.zeros(ncomp, dtype=bool)
            hard_c[lab[hard]] = True
            two = hard_c & (nt == 2) & (nd == 2)
            other = hard_c & ~two
            n_hard = int(np.count_nonzero(hard_c))
            largest = int((nt + nd)[hard_c].max())
            if solver == "auto" and int((nt + nd)[other].sum()) <= DENSE_FRAME_NODES:
                # the commonest conflict, 2 tracks × 2 detections, in closed form all at once,
                # and one dense solve of the union of the few other clusters
                sq = two[lab[hard]]
                if sq.any():
                    h = hard[sq]
                    chosen[rest[h[_solve_2x2(t[h], d[h], c[h], lab[h], u)]]] = True
                h = hard[~sq]
                if h.size:
                    chosen[rest[h[_solve_dense(t[h], d[h], c[h], u / 2)]]] = True
            elif solver == "sparse" or (
                solver == "auto" and (n_hard > SPARSE_CLUSTERS or largest > SMALL_NODES)
            ):
                sel = solve_sparse(t[hard], d[hard], c[hard], u / 2)
                chosen[rest[hard[sel]]] = True
            else:
                order = hard[np.argsort(lab[hard], kind="stable")]
                bounds = np.flatnonzero(first_per_group(lab[order]))
                for s, e in zip(bounds, [*bounds[1:], order.size], strict=True):
                    idx = order[s:e]
                    chosen[rest[idx[_solve_dense(t[idx], d[idx], c[idx], u / 2)]]] = True
    return ti[chosen], dj[chosen], cost[chosen]
