"""Gating: the (track, detection) pairs whose distance passes the gate, near-linear in N.

Two stages. A *spatial pre-gate* keeps only pairs whose centre distance is within each track's
radius bound (:func:`mvtrack.association.distances.gate_radius`), found on a uniform grid hash
of the detections (a KD-tree, :class:`scipy.spatial.cKDTree`, for the few unusually wide
gates); then the exact distance is computed on those pairs only and the gate applied. Small
problems skip the pre-gate and evaluate every pair.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from mvtrack.association.distances import (
    Distance,
    FloatArray,
    IntArray,
    TrackView,
    det_arrays,
    gate_radius,
    get_distance,
    pair_distance,
)
from mvtrack.types import Detections

#: up to this many track × detection pairs every pair is evaluated (the grid costs more)
DENSE_PAIRS = 4096


def _all_pairs(n: int, m: int) -> tuple[IntArray, IntArray]:
    ti, dj = np.divmod(np.arange(n * m, dtype=np.intp), max(m, 1))
    return ti, dj


def _expand_ranges(owner: IntArray, lo: IntArray, hi: IntArray) -> tuple[IntArray, IntArray]:
    """All ``(owner[r], k)`` with ``lo[r] <= k < hi[r]``, vectorised (no loop over ranges)."""
    counts = np.maximum(hi - lo, 0)
    total = int(counts.sum())
    rep = np.repeat(np.arange(owner.shape[0]), counts)
    starts = np.cumsum(counts) - counts
    pos = np.arange(total, dtype=np.intp) - starts[rep] + lo[rep]
    return owner[rep], pos


def _grid_pairs(
    track_xy: FloatArray, det_xy: FloatArray, radius: FloatArray, idx: IntArray
) -> tuple[IntArray, IntArray]:
    """Pairs of tracks ``idx`` and detections within ``radius``, by a uniform grid hash.

    Cells are ``max(radius[idx])`` wide, so a track's ball lies in its 3 × 3 block of cells.
    Detections are sorted by cell key ``row * ncols + col``; the three cells of one block row
    are contiguous in that order, so each track needs three ``searchsorted`` ranges. Everything
    is array arithmetic over all tracks at once.
    """
    txy = track_xy[idx]
    origin = np.minimum(txy.min(axis=0), det_xy.min(axis=0))
    extent = float((np.maximum(txy.max(axis=0), det_xy.max(axis=0)) - origin).max())
    cell = max(float(radius[idx].max()), extent / 65536.0, 1e-9)  # keys stay far below 2**63
    dc = np.floor((det_xy - origin) / cell).astype(np.int64) + 1  # +1: neighbours stay >= 0
    tc = np.floor((txy - origin) / cell).astype(np.int64) + 1
    ncols = int(max(dc[:, 0].max(), tc[:, 0].max())) + 2
    dkey = dc[:, 1] * ncols + dc[:, 0]
    order = np.argsort(dkey, kind="stable")
    skey = dkey[order]
    rows = (tc[:, 1, None] + np.array([-1, 0, 1])) * ncols  # (K, 3) block rows
    lo = np.searchsorted(skey, rows + (tc[:, 0, None] - 1), side="left").ravel()
    hi = np.searchsorted(skey, rows + (tc[:, 0, None] + 1), side="right").ravel()
    owner = np.repeat(idx, 3)
    ti, pos = _expand_ranges(owner, lo, hi)
    dj = order[pos]
    d = det_xy[dj] - track_xy[ti]
    keep = np.einsum("pi,pi->p", d, d) <= radius[ti] ** 2
    return ti[keep], dj[keep].astype(np.intp)


def _spatial_pairs(
    track_xy: FloatArray, det_xy: FloatArray, radius: FloatArray
) -> tuple[IntArray, IntArray]:
    """Pairs with ``|det − track| <= radius[track]``, sorted by track then detection.

    Tracks with a radius near the common one are found together on a uniform grid
    (:func:`_grid_pairs`); tracks with a much larger radius (long coasting, huge covariance)
    are queried one ball each in a KD-tree (:class:`scipy.spatial.cKDTree`), and unbounded
    ones take every detection, so one wide gate does not widen every track's search.
    """
    n, m = track_xy.shape[0], det_xy.shape[0]
    if n == 0 or m == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e.copy()
    rmin, rmax = float(radius.min()), float(radius.max())
    if np.isfinite(rmax) and rmax <= 2.0 * rmin:  # the usual case: one common radius scale
        ti, dj = _grid_pairs(track_xy, det_xy, radius, np.arange(n))
        order = np.argsort(ti.astype(np.int64) * m + dj, kind="stable")
        return ti[order], dj[order]
    finite = np.isfinite(radius)
    ref = np.median(radius[finite]) if finite.any() else 0.0
    common = finite & (radius <= 2.0 * ref)
    parts_t: list[IntArray] = []
    parts_d: list[IntArray] = []
    idx_common = np.flatnonzero(common)
    if idx_common.size:
        t, d = _grid_pairs(track_xy, det_xy, radius, idx_common)
        parts_t.append(t)
        parts_d.append(d)
    idx_wide = np.flatnonzero(finite & ~common)
    if idx_wide.size:  # few tracks: one ball query each, flattened without a Python loop body
        balls = cKDTree(det_xy).query_ball_point(track_xy[idx_wide], radius[idx_wide])
        counts = np.fromiter((len(b) for b in balls), dtype=np.intp, count=idx_wide.size)
        parts_t.append(np.repeat(idx_wide, counts))
        parts_d.append(
            np.fromiter((j for b in balls for j in b), dtype=np.intp, count=int(counts.sum()))
        )
    idx_inf = np.flatnonzero(~finite)
    if idx_inf.size:
        parts_t.append(np.repeat(idx_inf, m))
        parts_d.append(np.tile(np.arange(m, dtype=np.intp), idx_inf.size))
    ti = np.concatenate(parts_t)
    dj = np.concatenate(parts_d)
    order = np.argsort(ti.astype(np.int64) * m + dj, kind="stable")
    return ti[order], dj[order]


def candidate_pairs(
    view: TrackView,
    dets: Detections | FloatArray,
    distance: str | Distance = "euclidean",
    gate: float | None = None,
    *,
    method: Literal["auto", "dense", "grid"] = "auto",
    **params: Any,
) -> tuple[IntArray, IntArray, FloatArray]:
    """Gated (track, detection) pairs and their distances.

    Parameters
    ----------
    view : TrackView
        The ``N`` predicted tracks.
    dets : Detections or (M, 2) array
        The ``M`` detections of the frame.
    distance : str or Distance
        Name in :data:`mvtrack.association.distances.DISTANCES`.
    gate : float, optional
        Pairs with value ``<= gate`` pass; default: the distance's default gate.
    method : {"auto", "dense", "grid"}
        ``dense`` evaluates all ``N × M`` pairs; ``grid`` pre-gates spatially with each
        track's radius bound (uniform grid hash, KD-tree for unusually wide gates); ``auto``
        picks dense below :data:`DENSE_PAIRS` pairs.
    **params
        Parameters of the distance (e.g. ``rho`` for ``coupled``).

    Returns
    -------
    ti, dj : (P,) intp
        Track and detection rows of the gated pairs, sorted by track then detection.
    cost : (P,) float64
        Their distance values (NaN never passes).
    """
    dist = get_distance(distance)
    g = dist.gate if gate is None else float(gate)
    det_xy, _ = det_arrays(dets)
    n, m = len(view), det_xy.shape[0]
    if method not in ("auto", "dense", "grid"):
        raise ValueError(f"candidate_pairs: unknown method {method!r}")
    if not (np.isfinite(view.xy).all() and np.isfinite(det_xy).all()):
        raise ValueError("candidate_pairs: track or detection positions contain NaN or inf")
    if method == "dense" or (method == "auto" and n * m <= DENSE_PAIRS):
        ti, dj = _all_pairs(n, m)
    else:
        radius = gate_radius(dist, view, dets, g, **params)
        ti, dj = _spatial_pairs(view.xy, det_xy, radius)
    cost = pair_distance(dist, view, dets, ti, dj, **params)
    keep = cost <= g  # NaN compares False
    return ti[keep], dj[keep], cost[keep]


def gate_mask(
    view: TrackView,
    dets: Detections | FloatArray,
    distance: str | Distance = "euclidean",
    gate: float | None = None,
    **params: Any,
) -> NDArray[np.bool_]:
    """Dense (N, M) boolean gate matrix (for tests and small problems)."""
    det_xy, _ = det_arrays(dets)
    ti, dj, _ = candidate_pairs(view, dets, distance, gate, method="dense", **params)
    mask = np.zeros((len(view), det_xy.shape[0]), dtype=bool)
    mask[ti, dj] = True
    return mask
