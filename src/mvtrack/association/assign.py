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

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

ASSIGN_RULES = ("nearest", "greedy", "optimal")

#: with solver="auto", more conflicting clusters than this are solved in one sparse problem
SPARSE_CLUSTERS = 4
#: with solver="auto", clusters (or whole frames) of at most this many tracks + detections are
#: solved with a dense ``linear_sum_assignment``; larger ones with the sparse solver
SMALL_NODES = 64


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


def _first_per_group(group: IntArray) -> NDArray[np.bool_]:
    """For a sorted ``group`` array, True at the first element of each run."""
    first = np.ones(group.shape[0], dtype=bool)
    first[1:] = group[1:] != group[:-1]
    return first


def _nearest(ti: IntArray, dj: IntArray, cost: FloatArray) -> tuple[IntArray, ...]:
    order = np.lexsort((dj, cost, ti))  # by track, then cost, then detection row
    keep = order[_first_per_group(ti[order])]
    return ti[keep], dj[keep], cost[keep]


def _greedy(
    ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int, n_dets: int
) -> tuple[IntArray, ...]:
    """Greedy exclusive matching in increasing (cost, track, det) order.

    Vectorised in rounds: a pair that is the best remaining pair of both its track and its
    detection is accepted by the sequential greedy too (every earlier pair touches neither
    node), and removing accepted nodes leaves the greedy order of the rest unchanged.
    """
    order = np.lexsort((dj, ti, cost))
    t, d = ti[order], dj[order]
    rank = np.arange(t.shape[0])
    big = t.shape[0]
    acc: list[IntArray] = []
    while rank.size:
        best_t = np.full(n_tracks, big)
        best_d = np.full(n_dets, big)
        np.minimum.at(best_t, t, rank)
        np.minimum.at(best_d, d, rank)
        mutual = (best_t[t] == rank) & (best_d[d] == rank)
        acc.append(rank[mutual])
        used_t = np.zeros(n_tracks, dtype=bool)
        used_t[t[mutual]] = True
        used_d = np.zeros(n_dets, dtype=bool)
        used_d[d[mutual]] = True
        alive = ~(used_t[t] | used_d[d])
        t, d, rank = t[alive], d[alive], rank[alive]
    sel = order[np.concatenate(acc)] if acc else np.zeros(0, dtype=np.intp)
    return ti[sel], dj[sel], cost[sel]


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


def _solve_sparse(t: IntArray, d: IntArray, c: FloatArray, half_u: float) -> NDArray[np.bool_]:
    """Optimal exclusive matching of any number of clusters in one sparse LAPJVsp solve.

    Rows: tracks, then one dummy per detection; columns: detections, then one dummy per track.
    Edges: real pairs (cost), track → own dummy (u/2), detection dummy → detection (u/2), and
    the transposed pattern between dummies (0) so a perfect matching always exists. A constant
    offset keeps every weight non-zero (it adds the same amount to every perfect matching).
    """
    ut, lt = np.unique(t, return_inverse=True)
    ud, ld = np.unique(d, return_inverse=True)
    nt, nd = ut.size, ud.size
    p = t.shape[0]
    off = 1.0 + max(0.0, -float(c.min()))
    at = np.arange(nt)
    ad = np.arange(nd)
    rows = np.concatenate([lt, at, nt + ad, nt + ld])
    cols = np.concatenate([ld, nd + at, ad, nd + lt])
    w = np.concatenate(
        [c + off, np.full(nt, half_u + off), np.full(nd, half_u + off), np.full(p, off)]
    )
    g = csr_array(coo_array((w, (rows, cols)), shape=(nt + nd, nd + nt)))
    r, k = min_weight_full_bipartite_matching(g)
    real = (r < nt) & (k < nd)
    key = lt.astype(np.int64) * nd + ld
    order = np.argsort(key)
    hit = np.searchsorted(key[order], r[real].astype(np.int64) * nd + k[real])
    chosen = np.zeros(p, dtype=bool)
    chosen[order[hit]] = True
    return chosen


def _optimal(
    ti: IntArray,
    dj: IntArray,
    cost: FloatArray,
    n_tracks: int,
    n_dets: int,
    unmatched_cost: float | None,
    solver: str,
) -> tuple[IntArray, ...]:
    p = ti.shape[0]
    if unmatched_cost is None:  # every pair worth matching alone; see the module docstring
        u = 2.0 * float(np.abs(cost).max()) * (1.0 + 1e-9) + 1e-12
    else:
        u = float(unmatched_cost)
    deg_t = np.bincount(ti, minlength=n_tracks)
    deg_d = np.bincount(dj, minlength=n_dets)
    if deg_t.max() <= 1 and deg_d.max() <= 1:  # no conflicts at all: every pair stands alone
        keep = cost < u
        return ti[keep], dj[keep], cost[keep]
    if solver != "sparse" and np.count_nonzero(deg_t) + np.count_nonzero(deg_d) <= SMALL_NODES:
        chosen = _solve_dense(ti, dj, cost, u / 2)  # small frame: one dense solve, no clusters
        return ti[chosen], dj[chosen], cost[chosen]
    graph = coo_array(
        (np.ones(p), (ti, n_tracks + dj)), shape=(n_tracks + n_dets, n_tracks + n_dets)
    )
    ncomp, labels = connected_components(graph, directed=False)
    lab = labels[ti]
    nt = np.bincount(labels[:n_tracks][deg_t > 0], minlength=ncomp)
    nd = np.bincount(labels[n_tracks:][deg_d > 0], minlength=ncomp)
    trivial = (nt <= 1) | (nd <= 1)  # a star: every matching has at most one pair

    chosen = np.zeros(p, dtype=bool)
    # trivial clusters, all at once: the cheapest pair, if it beats leaving both unmatched
    tri = np.flatnonzero(trivial[lab])
    if tri.size:
        order = tri[np.lexsort((dj[tri], ti[tri], cost[tri], lab[tri]))]
        best = order[_first_per_group(lab[order])]
        chosen[best[cost[best] < u]] = True
    # conflicting clusters (at least two tracks and two detections)
    hard = np.flatnonzero(~trivial[lab])
    if hard.size:
        hard_c = ~trivial & (nt > 0)
        n_hard = int(np.count_nonzero(hard_c))
        largest = int((nt + nd)[hard_c].max())
        use_sparse = solver == "sparse" or (
            solver == "auto" and (n_hard > SPARSE_CLUSTERS or largest > SMALL_NODES)
        )
        if use_sparse:
            chosen[hard[_solve_sparse(ti[hard], dj[hard], cost[hard], u / 2)]] = True
        else:
            order = hard[np.argsort(lab[hard], kind="stable")]
            bounds = np.flatnonzero(_first_per_group(lab[order]))
            for s, e in zip(bounds, [*bounds[1:], order.size], strict=True):
                idx = order[s:e]
                chosen[idx[_solve_dense(ti[idx], dj[idx], cost[idx], u / 2)]] = True
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
        most :data:`SMALL_NODES` gated tracks + detections is one dense problem; otherwise
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
        t, d, c = _nearest(ti, dj, cost)
    elif rule == "greedy":
        t, d, c = _greedy(ti, dj, cost, n_tracks, n_dets)
    else:
        t, d, c = _optimal(ti, dj, cost, n_tracks, n_dets, unmatched_cost, solver)
    return _finish(t, d, c, n_tracks, n_dets)
