"""Assignment of detections to tracks from gated pairs: nearest (papers), greedy, optimal.

Input is the sparse output of :func:`mvtrack.association.gating.candidate_pairs`: aligned arrays
``ti`` (track rows), ``dj`` (detection rows) and ``cost`` of the gated pairs. Non-pairs are
forbidden.

Rules (``ASSIGN_RULES``):

- ``nearest`` — the papers' rule (paper 1 §"prediction-point decision", paper 2 Fig. 3): each
  track takes its nearest gated detection. Non-exclusive: two tracks may share a detection.
- ``greedy`` — exclusive nearest: pairs accepted in increasing cost, skipping used tracks or
  detections.
- ``optimal`` — global minimum-cost exclusive assignment (``scipy.optimize.linear_sum_assignment``
  or the sparse LAPJVsp of ``scipy.sparse.csgraph.min_weight_full_bipartite_matching``), solved
  per connected component of the gate graph so the cost grows with cluster size, not N × M.
  It minimises Σ cost over the matched pairs + u/2 per unmatched track and per unmatched
  detection (the cost-of-non-assignment form), i.e. it maximises Σ (u − cost) over the
  matches: a pair is only worth matching when its cost is below ``u``. Passing the gate as
  ``unmatched_cost`` gives the global-nearest-neighbour reading (maximise the total slack
  inside the gates). The default ``u = 2 · max |cost|`` makes every gated pair worth matching
  on its own and trades one more match against up to that much extra cost, close to
  "as many matches as possible, then least cost" without the huge penalty an exact
  maximum-cardinality solve needs (which makes the shortest-path solver very slow).

Ties are broken deterministically by (cost, track row, detection row).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_array, csr_array
from scipy.sparse.csgraph import connected_components, min_weight_full_bipartite_matching

from mvtrack import registry

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

#: the rules by name (:data:`mvtrack.registry.ASSIGN_RULES`)
ASSIGN_RULES = tuple(registry.ASSIGN_RULES)

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


@dataclass(frozen=True)
class Assignment:
    """Result of an assignment.

    Attributes
    ----------
    track, det : (K,) intp
        Matched track and detection rows, sorted by track. Under ``nearest`` a detection may
        appear more than once.
    cost : (K,) float64
        Distance of each matched pair.
    unmatched_tracks : intp array
        Track rows with no detection.
    unmatched_dets : intp array
        Detection rows used by no track.
    """

    track: IntArray
    det: IntArray
    cost: FloatArray
    unmatched_tracks: IntArray
    unmatched_dets: IntArray

    def __len__(self) -> int:
        return int(self.track.shape[0])

    def det_of_track(self, n_tracks: int) -> IntArray:
        """(n_tracks,) detection row per track, ``-1`` when unmatched."""
        out = np.full(n_tracks, -1, dtype=np.intp)
        out[self.track] = self.det
        return out


def _finish(t: IntArray, d: IntArray, c: FloatArray, n_tracks: int, n_dets: int) -> Assignment:
    order = np.argsort(t, kind="stable")
    t, d, c = t[order], d[order], c[order]
    used_t = np.zeros(n_tracks, dtype=bool)
    used_t[t] = True
    used_d = np.zeros(n_dets, dtype=bool)
    used_d[d] = True
    return Assignment(
        t.astype(np.intp),
        d.astype(np.intp),
        c.astype(np.float64),
        np.flatnonzero(~used_t),
        np.flatnonzero(~used_d),
    )


def first_per_group(group: IntArray) -> NDArray[np.bool_]:
    """For a sorted ``group`` array, True at the first element of each run."""
    first = np.ones(group.shape[0], dtype=bool)
    first[1:] = group[1:] != group[:-1]
    return first


def _rank(ti: IntArray, dj: IntArray, cost: FloatArray) -> IntArray:
    """Position of every pair in the total order (cost, track row, detection row)."""
    order = np.argsort(cost, kind="stable")
    sc = cost[order]
    if sc.size > 1 and np.any(sc[1:] == sc[:-1]):  # ties: break them by (track, detection)
        order = np.lexsort((dj, ti, cost))
    rank = np.empty(cost.shape[0], dtype=np.intp)
    rank[order] = np.arange(cost.shape[0])
    return rank


def _best_of(group: IntArray, rank: IntArray, size: int) -> IntArray:
    """(size,) smallest rank of each group (the largest intp where a group has no pair)."""
    best = np.full(size, np.iinfo(np.intp).max, dtype=np.intp)
    np.minimum.at(best, group, rank)
    return best


def _nearest(ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int) -> tuple[IntArray, ...]:
    rank = _rank(ti, dj, cost)
    keep = rank == _best_of(ti, rank, n_tracks)[ti]  # each track's first pair in the order
    return ti[keep], dj[keep], cost[keep]


def _greedy(
    ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int, n_dets: int
) -> tuple[IntArray, ...]:
    """Greedy exclusive matching in increasing (cost, track, det) order.

    Vectorised in rounds: a pair that is the best remaining pair of both its track and its
    detection is accepted by the sequential greedy too (every earlier pair touches neither
    node), and removing accepted nodes leaves the greedy order of the rest unchanged.
    """
    rank = _rank(ti, dj, cost)
    alive = np.arange(ti.shape[0])
    acc: list[IntArray] = []
    while alive.size:
        t, d, r = ti[alive], dj[alive], rank[alive]
        mutual = (_best_of(t, r, n_tracks)[t] == r) & (_best_of(d, r, n_dets)[d] == r)
        acc.append(alive[mutual])
        used_t = np.zeros(n_tracks, dtype=bool)
        used_t[t[mutual]] = True
        used_d = np.zeros(n_dets, dtype=bool)
        used_d[d[mutual]] = True
        alive = alive[~(used_t[t] | used_d[d])]
    sel = np.concatenate(acc) if acc else np.zeros(0, dtype=np.intp)
    return ti[sel], dj[sel], cost[sel]


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
    rank = _rank(ti, dj, cost)
    chosen = np.zeros(ti.shape[0], dtype=bool)
    alive = np.arange(ti.shape[0])
    for _ in range(_PEEL_ROUNDS):
        t, d, r = ti[alive], dj[alive], rank[alive]
        deg_t = np.bincount(t, minlength=n_tracks)
        deg_d = np.bincount(d, minlength=n_dets)
        acc = ((deg_d[d] == 1) & (_best_of(t, r, n_tracks)[t] == r)) | (
            (deg_t[t] == 1) & (_best_of(d, r, n_dets)[d] == r)
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


def _optimal(
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


def assign(
    ti: IntArray,
    dj: IntArray,
    cost: FloatArray,
    n_tracks: int,
    n_dets: int,
    rule: Literal["nearest", "greedy", "optimal"] = "optimal",
    *,
    unmatched_cost: float | None = None,
    solver: Literal["auto", "dense", "sparse"] = "auto",
) -> Assignment:
    """Assign detections to tracks from gated pairs.

    Parameters
    ----------
    ti, dj : (P,) int
        Track and detection rows of the allowed (gated) pairs; each pair at most once.
    cost : (P,) float
        Their costs (squared distances); NaN is not allowed.
    n_tracks, n_dets : int
        Number of tracks N and detections M.
    rule : {"nearest", "greedy", "optimal"}
        See the module docstring.
    unmatched_cost : float, optional
        ``optimal`` only: penalty ``u`` for leaving a pair's two ends unmatched (u/2 each);
        a sensible value is the gate. Default ``2 · max |cost|``.
    solver : {"auto", "dense", "sparse"}
        ``optimal`` only: one ``linear_sum_assignment`` per conflicting cluster (``dense``),
        one sparse LAPJVsp problem for all of them (``sparse``), or ``auto``: a frame with at
        most :data:`DENSE_FRAME_NODES` gated tracks + detections is one dense problem; otherwise
        dense per cluster when there are at most :data:`SPARSE_CLUSTERS` conflicting clusters
        of at most :data:`SMALL_NODES` nodes, else sparse.

    Returns
    -------
    Assignment
    """
    ti = np.asarray(ti, dtype=np.intp).ravel()
    dj = np.asarray(dj, dtype=np.intp).ravel()
    cost = np.asarray(cost, dtype=np.float64).ravel()
    if not (ti.shape == dj.shape == cost.shape):
        raise ValueError(
            f"assign: ti, dj and cost must have equal length, got {ti.size}, {dj.size}, {cost.size}"
        )
    if n_tracks < 0 or n_dets < 0:
        raise ValueError("assign: n_tracks and n_dets must be non-negative")
    if ti.size and (ti.min() < 0 or ti.max() >= n_tracks):
        raise ValueError(f"assign: track index out of range [0, {n_tracks})")
    if dj.size and (dj.min() < 0 or dj.max() >= n_dets):
        raise ValueError(f"assign: detection index out of range [0, {n_dets})")
    if np.isnan(cost).any():
        raise ValueError("assign: cost contains NaN")
    if rule not in ASSIGN_RULES:
        raise ValueError(f"assign: unknown rule {rule!r}; choose one of: {', '.join(ASSIGN_RULES)}")
    if solver not in ("auto", "dense", "sparse"):
        raise ValueError(f"assign: unknown solver {solver!r}")
    if ti.size == 0:
        e = np.zeros(0, dtype=np.intp)
        return _finish(e, e.copy(), np.zeros(0), n_tracks, n_dets)
    if rule == "nearest":
        t, d, c = _nearest(ti, dj, cost, n_tracks)
    elif rule == "greedy":
        t, d, c = _greedy(ti, dj, cost, n_tracks, n_dets)
    else:
        t, d, c = _optimal(ti, dj, cost, n_tracks, n_dets, unmatched_cost, solver)
    return _finish(t, d, c, n_tracks, n_dets)
