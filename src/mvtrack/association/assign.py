"""Assignment of detections to tracks through their gates: nearest (papers), greedy, optimal.

The tracker's association of one frame is :func:`associate`, a compiled kernel
(:func:`mvtrack.jit.kernel`) over the gate of :mod:`mvtrack.association.gate`:

1. **candidate pairs** inside the gate (:mod:`mvtrack.association.pairs`); a track held
   by template matching keeps only the detections centred in the box it stands in
   (:func:`standing_pairs`);
2. **stages by detection score** (ByteTrack's): every track against the high-score
   detections, then the tracks left over against the low-score ones;
3. **a rule** per stage (``ASSIGN_RULES``):

   - ``nearest`` — the papers' rule (paper 1 §"prediction-point decision", paper 2 Fig. 3):
     each track takes its nearest gated detection; non-exclusive, two tracks may share one;
   - ``greedy`` — exclusive nearest: pairs accepted in increasing cost;
   - ``optimal`` — the global nearest neighbour: the exclusive assignment that minimises
     ``Σ cost + u`` per pair of unmatched track and detection, ``u`` the gate (a gated pair
     is always worth matching on its own; a conflict is settled by the least total cost),
     solved per connected component of the gate graph — directly where a component is one
     pair, by enumeration where it is a small conflict, by SciPy's
     ``linear_sum_assignment`` where it is a larger one.

Ties are broken by (cost, track row, detection row). :func:`assign` is the same rules on
any list of pairs (the crossing experiment, :mod:`mvtrack.association.explain`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack import registry
from mvtrack.association.pairs import BY_QUADRATIC, frame_pairs
from mvtrack.jit import kernel, python_call

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = ["ASSIGN_RULES", "NO_STAND", "RULE_CODES", "Assignment", "assign", "associate",
           "standing_pairs"]

#: the rules by name (:data:`mvtrack.registry.ASSIGN_RULES`)
ASSIGN_RULES = tuple(registry.ASSIGN_RULES)
#: the rules as the kernels know them
RULE_CODES = {"nearest": 0, "greedy": 1, "optimal": 2}
_NEAREST, _GREEDY, _OPTIMAL = 0, 1, 2
#: detection classes of :func:`associate` (by calibrated score, :mod:`mvtrack.tracking.scores`)
DROPPED, LOW, HIGH = 0, 1, 2
#: conflicts of at most this many tracks and detections are solved by enumeration, larger ones
#: by SciPy (a call back from compiled code costs more than enumerating a small block)
_SMALL = 4


# ------------------------------------------------------------------------------------- rules


@kernel
def _lsa(block: FloatArray) -> tuple[IntArray, IntArray]:
    """SciPy's ``linear_sum_assignment`` of a dense block (from compiled code: a call back)."""
    with python_call(rows="intp[:]", cols="intp[:]"):
        r, c = linear_sum_assignment(block)
        rows, cols = r.astype(np.intp), c.astype(np.intp)
    return rows, cols


@kernel
def _small_block(block: FloatArray, unmatched: float) -> tuple[IntArray, IntArray]:
    """The exact assignment of a block of at most :data:`_SMALL` rows by enumeration: each row
    takes a distinct column or none (at cost ``unmatched``); the least total wins, the first
    found among equals (rows in order, columns in order, none last)."""
    r, c = block.shape
    choice = np.zeros(r, np.intp)  # an odometer over the columns 0..c (c: none)
    best = np.zeros(r, np.intp)
    best_cost = math.inf
    used = np.zeros(c + 1, np.intp)
    while True:
        total = 0.0
        ok = True
        used[:] = 0
        for i in range(r):
            j = choice[i]
            if j < c:
                if used[j]:
                    ok = False
                    break
                used[j] = 1
                total += block[i, j]
            else:
                total += unmatched
        if ok and total < best_cost:
            best_cost = total
            best[:] = choice
        i = r - 1
        while i >= 0:
            choice[i] += 1
            if choice[i] <= c:
                break
            choice[i] = 0
            i -= 1
        if i < 0:
            break
    rows = np.empty(r, np.intp)
    k = 0
    for i in range(r):  # a row on a non-pair (cost unmatched) stays unmatched
        if best[i] < c and block[i, best[i]] < unmatched:
            rows[k] = i
            k += 1
    rows = rows[:k]
    return rows, best[rows]


@kernel
def _find(parent: IntArray, a: int) -> int:
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@kernel
def solve(ti: IntArray, dj: IntArray, cost: FloatArray, n: int, m: int, rule: int,
          unmatched: float, det_index: IntArray) -> None:
    """Assign the pairs ``(ti, dj, cost)`` (sorted by track, then detection) by ``rule``;
    writes each matched track's detection into ``det_index`` (N,) in place.

    ``unmatched`` is the cost ``u`` of leaving a track and a detection unmatched
    (``optimal`` only).
    """
    p = ti.size
    if p == 0:
        return
    if rule == _NEAREST:  # each track its nearest; ties → the lower detection row
        best = np.full(n, math.inf)
        for q in range(p):
            if cost[q] < best[ti[q]]:
                best[ti[q]] = cost[q]
                det_index[ti[q]] = dj[q]
        return
    if rule == _GREEDY:
        order = np.argsort(cost, kind="mergesort")  # stable: (cost, track, detection)
        tused = np.zeros(n, np.bool_)
        dused = np.zeros(m, np.bool_)
        for q in order:
            if not tused[ti[q]] and not dused[dj[q]]:
                tused[ti[q]] = True
                dused[dj[q]] = True
                det_index[ti[q]] = dj[q]
        return
    # optimal: a pair whose track and detection have no other pair is matched as it is; the
    # rest by connected components of the gate graph (tracks 0..n-1, detections n..n+m-1)
    tdeg = np.zeros(n, np.intp)
    ddeg = np.zeros(m, np.intp)
    for q in range(p):
        tdeg[ti[q]] += 1
        ddeg[dj[q]] += 1
    rest = np.empty(p, np.intp)
    nr = 0
    for q in range(p):
        if tdeg[ti[q]] == 1 and ddeg[dj[q]] == 1:
            if cost[q] < unmatched:  # worth matching only below the cost of leaving both
                det_index[ti[q]] = dj[q]
        else:
            rest[nr] = q
            nr += 1
    if nr == 0:
        return
    rest = rest[:nr]
    parent = np.arange(n + m)
    for q in rest:
        a, b = _find(parent, ti[q]), _find(parent, n + dj[q])
        if a != b:
            parent[max(a, b)] = min(a, b)
    root = np.empty(nr, np.intp)
    size = np.zeros(n + m, np.intp)
    for e in range(nr):
        root[e] = _find(parent, ti[rest[e]])
        size[root[e]] += 1
    order = rest[np.argsort(root, kind="mergesort")]
    p = nr
    q0 = 0
    while q0 < p:
        r = _find(parent, ti[order[q0]])
        q1 = q0 + size[r]
        if q1 - q0 == 1:  # one pair: no conflict
            q = order[q0]
            if cost[q] < unmatched:
                det_index[ti[q]] = dj[q]
        else:
            idx = order[q0:q1]
            rows = np.unique(ti[idx])
            cols = np.unique(dj[idx])
            block = np.full((rows.size, cols.size), unmatched)
            for q in idx:
                a = np.searchsorted(rows, ti[q])
                b = np.searchsorted(cols, dj[q])
                block[a, b] = cost[q]
            if rows.size <= _SMALL and cols.size <= _SMALL:
                ra, ca = _small_block(block, unmatched)
            else:
                ra, ca = _lsa(block)
            for e in range(ra.size):
                if block[ra[e], ca[e]] < unmatched:
                    det_index[rows[ra[e]]] = cols[ca[e]]
        q0 = q1


# ------------------------------------------------------------------------------- one frame

#: no track is held where it stands (:func:`standing_pairs`)
NO_STAND = np.zeros((0, 4))


@kernel
def standing_pairs(ti: IntArray, dj: IntArray, c: FloatArray, stand: FloatArray,
                   dxy: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
    r"""The pairs left once each held track keeps only the detections centred in its box.

    A track held by template matching (state ``STOPPED``: a vehicle that stopped and faded
    into the background, SPEC §1.1 step 3) stands where its template matched. A detection of
    it has its centre inside the box it stands in, ``stand[i] = (x, y, w, h)``:

    .. math:: |x_d - x| \le w / 2, \quad |y_d - y| \le h / 2.

    A blob farther off is another object passing by (within paper 1's 20 px circle, or a
    gate that the filter has not yet closed), and a held track that took it would leave
    with it. ``stand`` (N, 4) has NaN rows for the tracks that are not held, or no rows when
    none is (:data:`NO_STAND`: the pairs are returned as they are).
    """
    if stand.shape[0] == 0:
        return ti, dj, c
    keep = np.ones(ti.size, np.bool_)
    for k in range(ti.size):
        i, j = ti[k], dj[k]
        if stand[i, 0] == stand[i, 0]:  # not NaN: held
            keep[k] = (abs(dxy[j, 0] - stand[i, 0]) <= stand[i, 2] / 2
                       and abs(dxy[j, 1] - stand[i, 1]) <= stand[i, 3] / 2)
    return ti[keep], dj[keep], c[keep]


@kernel
def associate(cx: FloatArray, S: FloatArray, cost: FloatArray, twh: FloatArray,
              dxy: FloatArray, dwh: FloatArray, dclass: NDArray[np.int8], gate: float,
              size_w: float, rule: int, stand: FloatArray,
              search: int = BY_QUADRATIC) -> IntArray:
    """The detection of every track in one frame (−1: none), in two stages by score.

    Parameters
    ----------
    cx, S : (N, 2), (N, 3)
        Gate centres and covariances (:class:`mvtrack.association.gate.Gate`).
    cost : (N, M) or (0, 0)
        The cost matrix of a gate searched in it (``coupled-literal``,
        :meth:`mvtrack.association.gate.Gate.dense`); empty for the others.
    twh, dxy, dwh : (N, 2), (M, 2), (M, 2)
        Track box sizes, detection centres and sizes.
    dclass : (M,) int8
        ``HIGH`` (2), ``LOW`` (1) or ``DROPPED`` (0): every track is matched against the high
        detections first, then the tracks left over against the low ones.
    gate, size_w, rule
        The gate on the value, the weight of the size term and the rule
        (:data:`RULE_CODES`).
    stand : (N, 4) or (0, 4)
        The box ``(x, y, w, h)`` each track held by template matching stands in (NaN rows
        for the others; no rows when none is held): such a track takes only a detection
        centred in it (:func:`standing_pairs`).
    search : int
        How the pairs are found (:func:`mvtrack.association.pairs.frame_pairs`; the
        gate's :attr:`~mvtrack.association.gate.Gate.search`): about each centre (default),
        among overlapping boxes (``iou``) or in ``cost``.
    """
    n, m = cx.shape[0], dxy.shape[0]
    det_index = np.full(n, -1, np.intp)
    if n == 0 or m == 0:
        return det_index
    tsel = np.ones(n, np.bool_)
    for stage in range(2):
        dsel = dclass == (HIGH if stage == 0 else LOW)
        if stage == 1:
            for i in range(n):
                tsel[i] = det_index[i] < 0
        if not dsel.any() or not tsel.any():
            continue
        ti, dj, c = frame_pairs(search, cx, S, cost, twh, tsel, dxy, dwh, dsel, gate, size_w)
        ti, dj, c = standing_pairs(ti, dj, c, stand, dxy)
        solve(ti, dj, c, n, m, rule, gate, det_index)
    return det_index


# ------------------------------------------------------------------------------ the Python API


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
        return int(self.track.size)

    def det_of_track(self, n: int) -> IntArray:
        """Each of ``n`` tracks' detection row (−1: none)."""
        out = np.full(n, -1, dtype=np.intp)
        out[self.track] = self.det
        return out


def assign(
    ti: IntArray, dj: IntArray, cost: FloatArray, n: int, m: int, rule: str = "optimal",
    unmatched_cost: float | None = None,
) -> Assignment:
    """Assign the candidate pairs ``(ti[p], dj[p])`` with values ``cost[p]`` by ``rule``.

    Parameters
    ----------
    ti, dj, cost : (P,) arrays
        Track rows, detection rows and values of the gated pairs (non-pairs are forbidden).
    n, m : int
        Numbers of tracks and detections.
    rule : {"nearest", "greedy", "optimal"}
    unmatched_cost : float, optional
        ``optimal`` only: the cost ``u`` of leaving a track and a detection unmatched (a pair
        is matched only if that lowers the total); default just above twice the largest
        ``|cost|``, so every pair is worth matching on its own and one more match is worth
        up to that much extra cost.

    Returns
    -------
    Assignment
    """
    if rule not in RULE_CODES:
        raise ValueError(f"unknown rule {rule!r}; choose one of: {', '.join(ASSIGN_RULES)}")
    ti = np.asarray(ti, dtype=np.intp)
    dj = np.asarray(dj, dtype=np.intp)
    cost = np.asarray(cost, dtype=np.float64)
    if not (ti.shape == dj.shape == cost.shape) or ti.ndim != 1:
        raise ValueError("ti, dj and cost must be 1-D arrays of equal length")
    if ti.size and (ti.min() < 0 or ti.max() >= n or dj.min() < 0 or dj.max() >= m):
        raise ValueError(f"pair rows out of range for n={n} tracks and m={m} detections")
    if np.isnan(cost).any():
        raise ValueError("cost must not contain NaN")
    order = np.lexsort((dj, ti))
    ti, dj, cost = ti[order], dj[order], cost[order]
    u = unmatched_cost
    if u is None:  # just above twice the largest value: every pair is worth matching
        big = 2.0 * float(np.abs(cost).max()) if cost.size else 0.0
        u = big * (1.0 + 1e-9) + 1e-12
    det_index = np.full(n, -1, np.intp)
    solve(ti, dj, cost, n, m, RULE_CODES[rule], float(u), det_index)
    track = np.flatnonzero(det_index >= 0)
    det = det_index[track]
    # the value of each chosen pair
    pos = np.searchsorted(ti * max(m, 1) + dj, track * max(m, 1) + det) if track.size else track
    used = np.zeros(m, bool)
    used[det] = True
    return Assignment(track.astype(np.intp), det.astype(np.intp), cost[pos],
                      np.flatnonzero(det_index < 0).astype(np.intp),
                      np.flatnonzero(~used).astype(np.intp))
