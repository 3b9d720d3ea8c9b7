"""Gating: the (track, detection) pairs whose distance passes the gate, near-linear in N.

Two stages. A *spatial pre-gate* keeps only pairs whose centre distance is within each track's
radius bound (:func:`mvtrack.association.distances.gate_radius`), found with a KD-tree over the
detections (:class:`scipy.spatial.cKDTree`); then the exact distance is computed on those pairs
only and the gate applied. Small problems skip the tree and evaluate every pair.
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

#: below this many track × detection pairs the dense path is used (tree overhead dominates)
DENSE_PAIRS = 4096


def _all_pairs(n: int, m: int) -> tuple[IntArray, IntArray]:
    ti, dj = np.divmod(np.arange(n * m, dtype=np.intp), max(m, 1))
    return ti, dj


def _spatial_pairs(
    track_xy: FloatArray, det_xy: FloatArray, radius: FloatArray
) -> tuple[IntArray, IntArray]:
    """Pairs with ``|det − track| <= radius[track]``, sorted by track then detection.

    Tracks with a radius near the common one are found together with one tree-against-tree
    query (:meth:`cKDTree.sparse_distance_matrix`); tracks with a much larger radius (long
    coasting, huge covariance) are queried one ball each, and unbounded ones take every
    detection, so one wide gate does not widen every track's search.
    """
    n, m = track_xy.shape[0], det_xy.shape[0]
    if n == 0 or m == 0:
        e = np.zeros(0, dtype=np.intp)
        return e, e.copy()
    finite = np.isfinite(radius)
    ref = np.median(radius[finite]) if finite.any() else 0.0
    common = finite & (radius <= 2.0 * ref)
    det_tree = cKDTree(det_xy)
    parts_t: list[IntArray] = []
    parts_d: list[IntArray] = []
    idx_common = np.flatnonzero(common)
    if idx_common.size:
        rmax = float(radius[idx_common].max())
        trk_tree = cKDTree(track_xy[idx_common])
        sdm = trk_tree.sparse_distance_matrix(det_tree, rmax, output_type="ndarray")
        ti = idx_common[sdm["i"]]
        keep = sdm["v"] <= radius[ti]
        parts_t.append(ti[keep])
        parts_d.append(sdm["j"][keep].astype(np.intp))
    idx_wide = np.flatnonzero(finite & ~common)
    if idx_wide.size:  # few tracks: one ball query each, flattened without a Python loop body
        balls = det_tree.query_ball_point(track_xy[idx_wide], radius[idx_wide])
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
    order = np.lexsort((dj, ti))
    return ti[order], dj[order]


def candidate_pairs(
    view: TrackView,
    dets: Detections | FloatArray,
    distance: str | Distance = "euclidean",
    gate: float | None = None,
    *,
    method: Literal["auto", "dense", "kdtree"] = "auto",
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
    method : {"auto", "dense", "kdtree"}
        ``dense`` evaluates all ``N × M`` pairs; ``kdtree`` pre-gates spatially with each
        track's radius bound; ``auto`` picks dense below :data:`DENSE_PAIRS` pairs.
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
    if method not in ("auto", "dense", "kdtree"):
        raise ValueError(f"candidate_pairs: unknown method {method!r}")
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
