"""Optimal bipartite matchings of sparse edge lists, as the scoring tools solve them densely.

The scoring tools solve one dense assignment problem per frame (motmetrics, TrackEval) or per
sequence (identity metrics): ``N × M`` cells for ``N`` ground-truth and ``M`` predicted boxes,
almost all of them "no pair". The optimum decomposes over the connected components of the
pair graph, so here an edge whose two ends have no other edge is taken at once and only the
rest — usually a few crowded spots — goes to a dense solver, on the rows and columns it
touches (in their original order) or component by component when that block would be large.
For the maximum-weight objective, edges that every optimal matching contains are taken first
(:func:`_dominant`), which settles nearly every frame of a crowd without a solver.
The optimum is the tools'; where several matchings are exactly optimal (equal sums to the
last bit, e.g. duplicated boxes) the one chosen may differ.

Two objectives:

* :func:`clear_matching` — the CLEAR-MOT rule of motmetrics' ``MOTAccumulator``: the most
  pairs, then the least total distance (its ``linear_sum_assignment`` on a matrix with NaN for
  "no pair");
* :func:`max_weight_matching` — the greatest total weight (``scipy.optimize.
  linear_sum_assignment`` on ``-weight`` with 0 for "no pair", as TrackEval's HOTA and its
  MOTChallenge distractor preprocessing).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mvtrack.types import FloatArray, IntArray

#: Largest dense block (cells) solved at once; larger ones are split into components.
_BLOCK_CELLS = 1 << 16

Solver = Callable[[FloatArray], tuple[IntArray, IntArray]]


def _clear_solver(block: FloatArray) -> tuple[IntArray, IntArray]:
    """The most pairs, then the least sum, of a block with NaN for "no pair".

    As motmetrics' ``lap.add_expensive_edges``: a missing pair costs more than any
    assignment with one pair more could save, ``2 r c + 1`` with ``r`` the smaller side and
    ``c`` one more than the largest |cost|; chosen missing pairs are dropped afterwards.
    """
    from scipy.optimize import linear_sum_assignment

    valid = np.isfinite(block)
    cost = block.copy()
    cost[~valid] = 2 * min(block.shape) * (np.abs(block[valid]).max() + 1) + 1
    r, c = linear_sum_assignment(cost)
    ok = valid[r, c]
    return r[ok], c[ok]


def _max_weight_solver(block: FloatArray) -> tuple[IntArray, IntArray]:
    from scipy.optimize import linear_sum_assignment

    r, c = linear_sum_assignment(-block)
    ok = block[r, c] > 0.0
    return r[ok], c[ok]


def _best_other(label: IntArray, weight: FloatArray, n: int) -> FloatArray:
    """For each edge, the greatest weight among the *other* edges at its end ``label``."""
    top1 = np.zeros(n)
    np.maximum.at(top1, label, weight)
    is_top = weight == top1[label]
    ties = np.bincount(label[is_top], minlength=n)
    top2 = np.zeros(n)
    np.maximum.at(top2, label[~is_top], weight[~is_top])
    # The heaviest edge of a label sees the second weight, unless another edge ties with it.
    return np.where(is_top & (ties[label] == 1), top2[label], top1[label])


def _dominant(r: IntArray, c: IntArray, w: FloatArray) -> tuple[IntArray, IntArray]:
    """Edges in every maximum-weight matching, and the edges left once their ends are taken.

    An edge heavier than the heaviest other edge at its row and the heaviest at its column
    together is in every optimal matching (exchanging it for those two would gain weight),
    so it is taken and its two ends removed; repeated until no edge qualifies. Returns the
    indices of the taken edges and of the remaining ones.
    """
    taken: list[IntArray] = []
    rest = np.arange(r.size)
    n_r, n_c = int(r.max()) + 1, int(c.max()) + 1
    while rest.size:
        rr, cr, wr = r[rest], c[rest], w[rest]
        sure = wr > _best_other(rr, wr, n_r) + _best_other(cr, wr, n_c)
        if not sure.any():
            break
        taken.append(rest[sure])
        used_r = np.zeros(n_r, dtype=bool)
        used_c = np.zeros(n_c, dtype=bool)
        used_r[rr[sure]] = used_c[cr[sure]] = True
        rest = rest[~used_r[rr] & ~used_c[cr]]
    return (np.concatenate(taken) if taken else np.zeros(0, np.int64)), rest


def _solve(
    rows: IntArray, cols: IntArray, values: FloatArray, fill: float, solver: Solver,
    reduce: bool,
) -> IntArray:
    """Indices of the chosen edges, ascending (edges given in row-major order)."""
    if rows.size == 0:
        return np.zeros(0, np.int64)
    r_ids, r = np.unique(rows, return_inverse=True)
    c_ids, c = np.unique(cols, return_inverse=True)
    r, c = r.reshape(-1), c.reshape(-1)
    chosen = []
    rest = np.arange(r.size)
    if reduce:
        sure, rest = _dominant(r, c, values)
        chosen.append(sure)
    rr, cr = r[rest], c[rest]
    alone = (np.bincount(rr)[rr] == 1) & (np.bincount(cr)[cr] == 1)
    chosen.append(rest[alone])
    rest = rest[~alone]
    if rest.size:
        groups = [rest]
        rr, cr = r[rest], c[rest]
        if np.unique(rr).size * np.unique(cr).size > _BLOCK_CELLS:
            from scipy.sparse import coo_matrix
            from scipy.sparse.csgraph import connected_components

            n_r = r_ids.size
            graph = coo_matrix(
                (np.ones(rest.size), (rr, n_r + cr)), shape=(n_r + c_ids.size,) * 2
            )
            _, label = connected_components(graph, directed=False)
            comp = label[rr]
            order = np.argsort(comp, kind="stable")
            groups = np.split(rest[order], np.flatnonzero(np.diff(comp[order])) + 1)
        for edges in groups:
            ur, br = np.unique(r[edges], return_inverse=True)
            uc, bc = np.unique(c[edges], return_inverse=True)
            block = np.full((ur.size, uc.size), fill)
            block[br, bc] = values[edges]
            lookup = np.full((ur.size, uc.size), -1, dtype=np.int64)
            lookup[br, bc] = edges
            i, j = solver(block)
            chosen.append(lookup[i, j])
    out = np.concatenate(chosen)
    out.sort()
    return out


def clear_matching(rows: IntArray, cols: IntArray, dist: FloatArray) -> IntArray:
    """The most pairs, then the least total ``dist`` (motmetrics' per-frame assignment).

    Parameters
    ----------
    rows, cols : (E,) int
        Ends of each candidate pair (any integer labels), sorted by row then column.
    dist : (E,) float
        Distance of each pair (finite).

    Returns
    -------
    (K,) int64
        Indices of the chosen pairs, ascending.
    """
    return _solve(rows, cols, dist, np.nan, _clear_solver, reduce=False)


def max_weight_matching(rows: IntArray, cols: IntArray, weight: FloatArray) -> IntArray:
    """The pairs of greatest total ``weight`` (> 0), as TrackEval's ``linear_sum_assignment``.

    Parameters
    ----------
    rows, cols : (E,) int
        Ends of each candidate pair (any integer labels), sorted by row then column.
    weight : (E,) float
        Weight of each pair; pairs of weight ≤ 0 are never chosen.

    Returns
    -------
    (K,) int64
        Indices of the chosen pairs, ascending.
    """
    positive = np.flatnonzero(weight > 0.0)
    picked = _solve(
        rows[positive], cols[positive], weight[positive], 0.0, _max_weight_solver, reduce=True
    )
    return positive[picked]
