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

Ties are broken deterministically by (cost, track row, detection row)
(:mod:`mvtrack.association.order`). The optimal solver is :mod:`mvtrack.association.optimal`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mvtrack import registry
from mvtrack.association.optimal import (
    DENSE_FRAME_NODES,
    SMALL_NODES,
    SPARSE_CLUSTERS,
    solve_optimal,
    solve_sparse,
)
from mvtrack.association.order import best_of, first_per_group, rank_pairs

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = [
    "ASSIGN_RULES",
    "DENSE_FRAME_NODES",
    "SMALL_NODES",
    "SPARSE_CLUSTERS",
    "Assignment",
    "assign",
    "first_per_group",
    "solve_sparse",
]

#: the rules by name (:data:`mvtrack.registry.ASSIGN_RULES`)
ASSIGN_RULES = tuple(registry.ASSIGN_RULES)


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


def _nearest(ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int) -> tuple[IntArray, ...]:
    rank = rank_pairs(ti, dj, cost)
    keep = rank == best_of(ti, rank, n_tracks)[ti]  # each track's first pair in the order
    return ti[keep], dj[keep], cost[keep]


def _greedy(
    ti: IntArray, dj: IntArray, cost: FloatArray, n_tracks: int, n_dets: int
) -> tuple[IntArray, ...]:
    """Greedy exclusive matching in increasing (cost, track, det) order.

    Vectorised in rounds: a pair that is the best remaining pair of both its track and its
    detection is accepted by the sequential greedy too (every earlier pair touches neither
    node), and removing accepted nodes leaves the greedy order of the rest unchanged.
    """
    rank = rank_pairs(ti, dj, cost)
    alive = np.arange(ti.shape[0])
    acc: list[IntArray] = []
    while alive.size:
        t, d, r = ti[alive], dj[alive], rank[alive]
        mutual = (best_of(t, r, n_tracks)[t] == r) & (best_of(d, r, n_dets)[d] == r)
        acc.append(alive[mutual])
        used_t = np.zeros(n_tracks, dtype=bool)
        used_t[t[mutual]] = True
        used_d = np.zeros(n_dets, dtype=bool)
        used_d[d[mutual]] = True
        alive = alive[~(used_t[t] | used_d[d])]
    sel = np.concatenate(acc) if acc else np.zeros(0, dtype=np.intp)
    return ti[sel], dj[sel], cost[sel]


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
        t, d, c = solve_optimal(ti, dj, cost, n_tracks, n_dets, unmatched_cost, solver)
    return _finish(t, d, c, n_tracks, n_dets)
