"""Gating and optimal assignment for disc-shaped gates: the tracker's default association.

For the distances whose gate is a disc around the prediction — ``euclidean`` (eq. (8) of
paper 2) and ``mahalanobis`` with an isotropic innovation covariance ``S = s I`` (what the
per-axis filters give, SPEC E2.3) — the tracker gates and assigns here with a small, fixed
number of array operations per frame. Everything else goes through
:mod:`mvtrack.association`. :func:`gate_pairs` mirrors
:func:`mvtrack.association.gating.candidate_pairs` with the ``euclidean`` and ``mahalanobis``
distances, :func:`optimal` :func:`mvtrack.association.assign.assign` with rule ``optimal`` and
``unmatched_cost = 2 half_u``; ``tests/association/test_discs.py`` pins them equal. The
tracker's box-size scaling adds per-axis factors (an axis-aligned ellipse) that
:mod:`mvtrack.association` does not have; that case is checked against a hand computation.

Gating is dense (an ``N × M`` matrix by broadcasting) for small problems, from a vertical band
around each track (:func:`mvtrack.association.gating.band_pairs`) for medium ones and spatial
(the grid of :func:`mvtrack.association.gating.spatial_pairs`) for large ones, so the number
of candidate pairs and the cost grow near-linearly with ``N``.

The ``optimal`` rule minimises the total cost of the matched gated pairs plus a penalty
``u/2`` for every track and every detection left unmatched — the rule of
:func:`mvtrack.association.assign` with ``unmatched_cost=u``; the tracker uses ``u = 2 ×
gate``, so any gated pair is worth matching on its own, and only chains of re-assignments
that cost more than they gain are refused. It is solved in tiers:

1. *stars* — components of the gate graph with one track or one detection (isolated pairs
   included; most pairs in sparse scenes): the cheapest pair, vectorised;
2. the remaining *conflict* pairs: one dense ``linear_sum_assignment`` on their compact matrix
   when it is small, else one sparse LAPJVsp solve of all of them
   (:func:`mvtrack.association.assign.solve_sparse`, the solver of ``assign``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.association.assign import first_per_group, solve_sparse
from mvtrack.association.gating import band_pairs, spatial_pairs

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: up to this many track × detection pairs the gate is evaluated densely
DENSE_GATE = 6_400
#: up to this many track × detection pairs candidates come from a band in x (one sort), above
#: it from a grid of cells (crossovers measured at ~80 and ~700 targets in 1920 × 1080)
DENSE_PAIRS = 400_000
#: up to this many track × detection pairs one dense assignment solves the whole frame
DENSE_LSA = 2_500
#: up to this many cells the conflict pairs are solved in one dense assignment
DENSE_CONFLICT = 10_000

_EMPTY = np.zeros(0, dtype=np.intp)

#: the box-size term of the cost: ``(track wh (N, 2), detection wh (M, 2), weight)``, and
#: optionally a fourth element, the size gate ``ρ > 1`` (pairs whose heights differ by more
#: than the factor ``ρ`` or widths by more than ``ρ²`` are not gated, :func:`size_apart`),
#: and a fifth, the tolerance ``ε`` of the partial views that the size gate lets through
#: (:func:`partial_views`)
SizeTerm = (
    tuple[FloatArray, FloatArray, float]
    | tuple[FloatArray, FloatArray, float, float]
    | tuple[FloatArray, FloatArray, float, float, float]
)



def size_term(
    twh: FloatArray, dwh: FloatArray, weight: float, size_gate: float | None,
    partial: float | None = None,
) -> SizeTerm | None:
    """The box-size term of a Euclidean stage for tracks of box sizes ``twh`` against
    detections of sizes ``dwh``: ``weight`` (``TrackerConfig.size_weight``), the size gate
    ``size_gate`` (``TrackerConfig.size_gate``) and the tolerance of the partial views it lets
    through (``TrackerConfig.partial_tolerance``), or ``None`` when there is none of them."""
    if size_gate is not None:
        if partial is not None:
            return (twh, dwh, weight, size_gate, partial)
        return (twh, dwh, weight, size_gate)
    return (twh, dwh, weight) if weight else None


def size_apart(twh: FloatArray, dwh: FloatArray, rho: float) -> NDArray[np.bool_]:
    """Boxes whose heights differ by more than the factor ``rho`` or widths by more than
    ``rho²`` (``twh``, ``dwh`` broadcast against each other: a matrix or aligned pairs; NaN
    sizes are never apart).

    The width is gated more loosely because it changes with the pose — a walker's stride, a
    vehicle that turns — while the height changes with the distance: on the ground-truth
    boxes of KITTI-17 (10 fps), 0.7 % of a person's boxes differ in width from the average of
    their earlier ones (size smoothing 0.5) by more than 1.5, none in height; on the
    detectors' boxes of the MOT15 sequences (one aspect ratio) both tests are the same.
    """
    # max(a, b) > ρ min(a, b)  ⟺  |ln a − ln b| > ln ρ: logs of the (N, 2) and (M, 2) sizes,
    # then three (N, M) operations per axis instead of five on (N, M, 2)
    lt, ld = np.log(twh), np.log(dwh)
    limit = math.log(rho)
    dw = np.abs(ld[..., 0] - lt[..., 0])
    dw *= 0.5  # |ln w_d − ln w_t| > 2 ln ρ
    dh = np.abs(ld[..., 1] - lt[..., 1])
    return np.maximum(dw, dh, out=dw) > limit


def partial_views(
    twh: FloatArray, dwh: FloatArray, dx: FloatArray, dy: FloatArray, eps: float
) -> NDArray[np.bool_]:
    r"""Detections that may be the visible part of the track's object: the lower part of a
    person partly hidden, standing where the track stands.

    A detection box (centre offset ``(dx, dy)`` from the track's centre, size ``dwh``) smaller
    than the track's box ``twh`` in height is a partial view when its bottom edge lies within
    ``ε h_t`` of the track's and it lies inside the track's box widened by ``ε`` along x:

    .. math::

        h_d < h_t, \qquad |dy + h_d/2 - h_t/2| \le \varepsilon h_t, \qquad
        |dx| + w_d/2 \le (1 + \varepsilon)\, w_t/2.

    On a ground plane the bottom edge is the foot point, which fixes the distance from the
    camera: a smaller box whose feet stand where the track's do is not a person farther away.
    Arrays broadcast as in :func:`size_apart`.
    """
    tw, th = twh[..., 0], twh[..., 1]
    dw, dh = dwh[..., 0], dwh[..., 1]
    foot = np.abs(dy + 0.5 * (dh - th)) <= eps * th
    foot &= dh < th
    foot &= np.abs(dx) + 0.5 * dw <= (0.5 + 0.5 * eps) * tw
    return foot


def _cost(dx: FloatArray, dy: FloatArray, scale: FloatArray | None) -> FloatArray:
    """``Δᵀ S⁻¹ Δ`` for track rows along axis 0 of ``dx, dy`` (new array).

    ``scale``: ``None`` (``S = I``: squared Euclidean distance, eq. (8) of paper 2), ``(N,)``
    (``S_i = s_i I``) or ``(N, 2)`` (``S_i = diag(s_i)``, an axis-aligned ellipse).
    """
    if scale is None:
        return dx * dx + dy * dy  # eq. (8) of paper 2, squared
    extra = (slice(None),) + (None,) * (dx.ndim - 1)
    if scale.ndim == 1:
        return (dx * dx + dy * dy) / scale[extra]
    return dx * dx / scale[:, 0][extra] + dy * dy / scale[:, 1][extra]


def _isolated(ok: NDArray[np.bool_]) -> tuple[IntArray, IntArray] | None:
    """The gated pairs ``(rows, cols)`` of ``ok`` if every track and every detection has at
    most one gated partner, else None. Isolated pairs need no solver: the optimal assignment
    takes each of them (each costs less than leaving both unmatched)."""
    r, c = ok.nonzero()
    k = r.size
    if k == 0 or (np.count_nonzero(np.bincount(r)) == k and np.count_nonzero(np.bincount(c)) == k):
        return r, c
    return None


def _size_matrix(size: SizeTerm, scale: FloatArray | None) -> FloatArray:
    """Unweighted size term ``Δwᵀ diag(scale)⁻¹ Δw`` of every track × detection pair."""
    twh, dwh = size[0], size[1]
    return _cost(dwh[:, 0] - twh[:, 0, None], dwh[:, 1] - twh[:, 1, None], scale)


def _size_apart(
    size: SizeTerm | None, twh: FloatArray, dwh: FloatArray, dx: FloatArray, dy: FloatArray
) -> NDArray[np.bool_] | None:
    """Pairs that the size gate ``size[3]`` refuses: boxes that differ by more than that
    factor in height or its square in width (:func:`size_apart`), less the partial views
    (:func:`partial_views`, tolerance ``size[4]``) — aligned pairs of sizes ``twh``, ``dwh``
    and centre offsets ``dx``, ``dy``; ``None`` without a size gate."""
    if size is None or len(size) < 4:
        return None
    apart = size_apart(twh, dwh, size[3])
    if len(size) > 4 and np.count_nonzero(apart):
        apart &= ~partial_views(twh, dwh, dx, dy, size[4])
    return apart


def _mask_apart(
    cost: FloatArray, size: SizeTerm | None, dx: FloatArray, dy: FloatArray, reach: float
) -> NDArray[np.bool_] | None:
    """Set the costs of the track × detection pairs that the size gate refuses to ``inf``
    (in place, ``cost`` (N, M); ``dx``, ``dy`` the detections' offsets from the tracks);
    returns those pairs, or ``None`` without a size gate. The partial views are looked for
    among the pairs with ``cost <= reach`` only (the widest gate this mask serves): the others
    are never gated whatever their sizes."""
    if size is None or len(size) < 4:
        return None
    twh, dwh = size[0], size[1]
    apart = size_apart(twh[:, None], dwh[None], size[3])
    if len(size) > 4:  # the pairs apart but near enough to be gated, less the partial views
        i, j = (apart & (cost <= reach)).nonzero()
        if i.size:
            apart[i, j] = _size_apart(size, twh.take(i, 0), dwh.take(j, 0), dx[i, j], dy[i, j])
    cost[apart] = np.inf
    return apart


def _add_size(cost: FloatArray, s: FloatArray, weight: float, cap: float) -> FloatArray:
    """``cost + weight · min(s, cap)``: with ``weight < 1`` and ``cap`` the gate, a gated pair
    still costs less than ``2 gate`` (leaving its track and detection unmatched)."""
    return cost + weight * np.minimum(s, cap)


def gate_pairs(
    txy: FloatArray, dxy: FloatArray, scale: FloatArray | None, gate: float,
    size: SizeTerm | None = None,
) -> tuple[IntArray, IntArray, FloatArray]:
    """Gated pairs ``(ti, dj, cost)`` with ``cost = Δᵀ S_i⁻¹ Δ <= gate``, ``Δ = z_j − x̄_i``.

    ``scale`` is ``None`` for the Euclidean distance (eq. (8) of paper 2, cost in px², the
    values of :func:`mvtrack.association.distances.euclidean`), the innovation variance
    ``s_i`` (N,) for the Mahalanobis distance with ``S_i = s_i I`` (cost χ²-distributed with
    2 degrees of freedom, the values of ``mahalanobis`` there), or per-axis factors ``(N, 2)``
    (``S_i = diag(s_i)``: the tracker's Euclidean gate stretched with the box size).

    ``size = (track wh, detection wh, weight)`` adds ``weight · min(Δwᵀ S_i⁻¹ Δw, gate)``
    (``Δw`` the difference of the box sizes, ``S_i`` as above: ``None`` or per-axis) to the
    cost of every gated pair; the gate itself stays on the position.
    """
    n, m = txy.shape[0], dxy.shape[0]
    if n == 0 or m == 0:
        return _EMPTY, _EMPTY, np.zeros(0)
    if n * m <= DENSE_GATE:
        dx, dy = dxy[:, 0] - txy[:, 0, None], dxy[:, 1] - txy[:, 1, None]
        cost = _cost(dx, dy, scale)
        _mask_apart(cost, size, dx, dy, gate)
        ti, dj = np.nonzero(cost <= gate)
        return ti, dj, _pair_size(ti, dj, cost[ti, dj], scale, gate, size)
    if scale is None:
        radius = np.empty(n)
        radius.fill(np.sqrt(gate))
    else:
        radius = np.sqrt(gate * (scale if scale.ndim == 1 else scale.max(axis=1)))
    if n * m <= DENSE_PAIRS:
        rx = radius if scale is None or scale.ndim == 1 else np.sqrt(gate * scale[:, 0])
        ti, dj = band_pairs(txy, dxy, rx)
    else:
        ti, dj = spatial_pairs(txy, dxy, radius)
    d = dxy.take(dj, 0) - txy.take(ti, 0)
    cost = _cost(d[:, 0], d[:, 1], None if scale is None else scale.take(ti, 0))
    keep = cost <= gate
    ti, dj, cost, d = ti.compress(keep), dj.compress(keep), cost.compress(keep), d[keep]
    if size is not None:
        apart = _size_apart(size, size[0].take(ti, 0), size[1].take(dj, 0), d[:, 0], d[:, 1])
        if apart is not None:
            keep = ~apart
            ti, dj, cost = ti.compress(keep), dj.compress(keep), cost.compress(keep)
    return ti, dj, _pair_size(ti, dj, cost, scale, gate, size)


def _pair_size(
    ti: IntArray, dj: IntArray, cost: FloatArray, scale: FloatArray | None, gate: float,
    size: SizeTerm | None,
) -> FloatArray:
    """``cost`` of the pairs plus their size term (:func:`gate_pairs`)."""
    if size is None or ti.size == 0:
        return cost
    twh, dwh, weight = size[0], size[1], size[2]
    d = dwh.take(dj, 0) - twh.take(ti, 0)
    s = _cost(d[:, 0], d[:, 1], None if scale is None else scale.take(ti, 0))
    return _add_size(cost, s, weight, gate)


def dense_optimal(
    txy: FloatArray, dxy: FloatArray, scale: FloatArray | None, gate: float,
    size: SizeTerm | None = None,
) -> tuple[IntArray, IntArray]:
    """Gate and solve a small problem in one dense ``linear_sum_assignment``.

    Same result as :func:`gate_pairs` followed by :func:`optimal` with ``half_u = gate``: a
    forbidden cell costs ``u = 2 gate``, i.e. leaving both its track and its detection
    unmatched, which makes the rectangular problem equivalent to the penalised one (up to a
    constant). ``size`` as in :func:`gate_pairs`. Returns matched (track, detection) rows.
    """
    dx, dy = dxy[:, 0] - txy[:, 0, None], dxy[:, 1] - txy[:, 1, None]
    cost = _cost(dx, dy, scale)
    _mask_apart(cost, size, dx, dy, gate)
    ok = cost <= gate  # NaN never passes
    pairs = _isolated(ok)
    if pairs is not None:
        return pairs
    out = ~ok
    if size is not None:
        cost = _add_size(cost, _size_matrix(size, scale), size[2], gate)
    u = 2.0 * gate
    cost[out] = u
    rows, cols = linear_sum_assignment(cost)
    keep = cost[rows, cols] < u
    return rows[keep], cols[keep]


def dense_two_stage(
    txy: FloatArray, dxy: FloatArray, scale: FloatArray | None, gate: float, gate2: float,
    scale2: FloatArray | None = None, size: SizeTerm | None = None,
) -> tuple[IntArray, IntArray, IntArray]:
    """:func:`dense_optimal`, then a second stage on what is left.

    The tracks and detections left unmatched by the first stage are assigned again with the
    Euclidean gate ``gate2`` (px²) on the squared distance (with ``scale2`` (N,) or (N, 2)
    when given, as ``scale`` of :func:`gate_pairs`: the tracker's box-size factors), from the
    same differences. ``size`` as in :func:`gate_pairs` (normalised by ``scale2``, capped at
    each stage's gate; only with the Euclidean ``scale``, i.e. ``scale is scale2``).
    Returns all matched (track, detection) rows, first stage first, and the unassigned
    detection rows.
    """
    dx = dxy[:, 0] - txy[:, 0, None]
    dy = dxy[:, 1] - txy[:, 1, None]
    cost = _cost(dx, dy, scale)  # eq. (8) of paper 2, squared (over S)
    plain = scale is None and scale2 is None
    # both stages (d2 below is cost, or masked again); the second stage's costs are on the
    # first's scale when scale2 is scale (the tracker's Euclidean stages), else all pairs count
    reach = max(gate, gate2) if plain or scale2 is scale else np.inf
    apart = _mask_apart(cost, size, dx, dy, reach)
    d2 = cost if plain else None  # the second stage's costs (copied before cost changes)
    ok = cost <= gate  # NaN never passes
    s = None
    pairs = _isolated(ok)
    if pairs is not None:
        rows, cols = pairs
    else:
        if size is not None:
            s = _size_matrix(size, scale2)
            cost = _add_size(cost, s, size[2], gate)
        elif d2 is not None:
            cost = cost.copy()
        u = 2.0 * gate
        cost[~ok] = u
        rows, cols = linear_sum_assignment(cost)
        keep = cost[rows, cols] < u
        rows, cols = rows[keep], cols[keep]
    n, m = cost.shape
    free_d = np.empty(m, dtype=bool)
    free_d.fill(True)
    free_d[cols] = False
    if rows.size == n or rows.size == m:
        return rows, cols, free_d.nonzero()[0]
    if d2 is not None and gate <= gate2 and np.count_nonzero(d2 <= gate2) == rows.size:
        # the pairs within gate2 are the matched ones (each within gate): no second stage
        return rows, cols, free_d.nonzero()[0]
    free_t = np.empty(n, dtype=bool)
    free_t.fill(True)
    free_t[rows] = False
    lt, ld = free_t.nonzero()[0], free_d.nonzero()[0]
    if d2 is not None:
        sub = d2.take(lt, 0).take(ld, 1)
    else:
        sub = _cost(dx.take(lt, 0).take(ld, 1), dy.take(lt, 0).take(ld, 1),
                    None if scale2 is None else scale2.take(lt, 0))
        if apart is not None:
            sub[apart.take(lt, 0).take(ld, 1)] = np.inf
    ok = sub <= gate2
    if not np.count_nonzero(ok):
        return rows, cols, ld
    pairs = _isolated(ok)
    if pairs is not None:
        r2, c2 = pairs
    else:
        if size is not None:
            sz = _size_matrix(size, scale2) if s is None else s
            sub = _add_size(sub, sz.take(lt, 0).take(ld, 1), size[2], gate2)
        u2 = 2.0 * gate2
        sub[~ok] = u2
        r2, c2 = linear_sum_assignment(sub)
        keep = sub[r2, c2] < u2
        r2, c2 = r2[keep], c2[keep]
    r2, c2 = lt[r2], ld[c2]
    free_d[c2] = False
    return np.concatenate([rows, r2]), np.concatenate([cols, c2]), free_d.nonzero()[0]


def _min_per(key: IntArray, cost: FloatArray, other: IntArray, sel: IntArray) -> IntArray:
    """Among pairs ``sel``, the cheapest per value of ``key`` (ties: lowest ``other``)."""
    order = sel[np.lexsort((other[sel], cost[sel], key[sel]))]
    return order[first_per_group(key[order])]


def optimal(
    ti: IntArray, dj: IntArray, cost: FloatArray, n: int, m: int, half_u: float
) -> tuple[IntArray, IntArray]:
    """Minimum of Σ cost(matched pairs) + ``half_u`` × (unmatched tracks + detections).

    ``ti, dj, cost`` are the gated pairs (each pair at most once, ``cost < 2 half_u``); ``n``
    tracks and ``m`` detections. Returns the matched (track, detection) rows.
    """
    if ti.shape[0] == 0:
        return _EMPTY, _EMPTY
    deg_t = np.bincount(ti, minlength=n)
    deg_d = np.bincount(dj, minlength=m)
    # a track all of whose detections are its alone is the centre of a star component
    t_conf = np.bincount(ti, weights=deg_d[dj] > 1, minlength=n) > 0
    d_conf = np.bincount(dj, weights=deg_t[ti] > 1, minlength=m) > 0
    t_star = ~t_conf[ti]  # pairs of components with one track (or 1-1)
    d_star = ~d_conf[dj] & ~t_star  # components with one detection and several tracks
    parts = []
    if np.count_nonzero(t_star):
        parts.append(_min_per(ti, cost, dj, t_star.nonzero()[0]))
    if np.count_nonzero(d_star):
        parts.append(_min_per(dj, cost, ti, d_star.nonzero()[0]))
    hard = (~(t_star | d_star)).nonzero()[0]
    if hard.size:
        parts.append(hard[_solve_conflicts(ti[hard], dj[hard], cost[hard], half_u, n, m)])
    chosen = np.concatenate(parts) if len(parts) > 1 else parts[0]
    return ti[chosen], dj[chosen]


def _compact(idx: IntArray, size: int) -> tuple[int, IntArray]:
    """Number of distinct values of ``idx`` (all in ``[0, size)``) and each one's rank among
    them: ``np.unique(idx, return_inverse=True)`` without sorting."""
    seen = np.zeros(size, dtype=np.intp)
    seen[idx] = 1
    rank = np.cumsum(seen) - 1
    return int(rank[-1]) + 1, rank[idx]


def _solve_conflicts(
    t: IntArray, d: IntArray, c: FloatArray, half_u: float, n: int, m: int
) -> IntArray:
    """Positions (into ``t``) of the optimal pairs of the conflict components (``t < n``,
    ``d < m``)."""
    nt, lt = _compact(t, n)
    nd, ld = _compact(d, m)
    p = t.size
    if nt * nd <= DENSE_CONFLICT:
        a = np.empty((nt, nd))
        a.fill(2.0 * half_u)  # forbidden = leave both unmatched
        a[lt, ld] = c
        pos = np.empty((nt, nd), dtype=np.intp)
        pos.fill(-1)
        pos[lt, ld] = np.arange(p)
        rows, cols = linear_sum_assignment(a)
        got = pos[rows, cols]
        return got[got >= 0]
    return solve_sparse(t, d, c, half_u, (nt, lt, nd, ld)).nonzero()[0]  # the same, sparse
