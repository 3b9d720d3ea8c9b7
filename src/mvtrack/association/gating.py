"""Gating: the (track, detection) pairs whose distance passes the gate, near-linear in N.

Two stages. A *spatial pre-gate* proposes the pairs whose centre distance may be within each
track's radius bound (:func:`mvtrack.association.distances.gate_radius`): the one spatial
index of the package, :func:`spatial_pairs` (a uniform grid of the detections, a KD-tree,
:class:`scipy.spatial.cKDTree`, for the few unusually wide gates), or :func:`band_pairs` (a
vertical band, for medium problems of the disc-gate path); then the exact distance is
computed on those pairs only and the gate applied. Small problems skip the pre-gate and
evaluate every pair. :func:`candidate_pairs` serves every distance;
:mod:`mvtrack.association.discs` uses the same pre-gates for the disc-shaped gates.
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
    resolve_gate,
)
from mvtrack.types import Detections

#: up to this many track × detection pairs every pair is evaluated (the grid costs more)
DENSE_PAIRS = 4096


def _all_pairs(n: int, m: int) -> tuple[IntArray, IntArray]:
    ti, dj = np.divmod(np.arange(n * m, dtype=np.intp), max(m, 1))
    return ti, dj


#: the 3 × 3 block of grid cells around a cell
_NEIGHBOURS = np.array([(dx, dy) for dy in (-1, 0, 1) for dx in (-1, 0, 1)], dtype=np.int64)


def band_pairs(txy: FloatArray, dxy: FloatArray, rx: FloatArray) -> tuple[IntArray, IntArray]:
    """Candidate pairs: every detection with ``|x_j − x_i| <= rx_i`` (a vertical band around
    track ``i``), found by binary search in the detections sorted by x. The caller filters the
    pairs by their exact distance; for a few hundred targets this is cheaper than the dense
    ``N × M`` matrix and than the grid of :func:`spatial_pairs`.
    """
    order = np.argsort(dxy[:, 0], kind="stable")
    xs = dxy[:, 0].take(order)
    tx = txy[:, 0]
    start = np.searchsorted(xs, tx - rx, side="left")
    count = np.searchsorted(xs, tx + rx, side="right") - start
    np.maximum(count, 0, out=count)  # a NaN radius or position finds nothing
    total = int(count.sum())
    ti = np.repeat(np.arange(txy.shape[0]), count)
    # positions start[i], start[i] + 1, ... for every track i
    run_start = np.repeat(start - (np.cumsum(count) - count), count)
    return ti, order[run_start + np.arange(total)]


def spatial_pairs(
    txy: FloatArray, dxy: FloatArray, radius: FloatArray
) -> tuple[IntArray, IntArray]:
    """Candidate pairs: every detection within ``radius_i`` of track ``i`` (and a few more).

    Detections are sorted into square cells of side ``c`` (the largest radius up to 1.25
    times the median); each track with ``radius_i <= c`` looks at the 3 × 3 cells around its
    own, found by binary search in the sorted cell keys, so the work is proportional to the
    number of tracks and candidate pairs. The few tracks with a wider gate (long coasting)
    are queried in a KD-tree. The caller filters the pairs by their exact distance.
    """
    finite = np.isfinite(radius)
    ref = 1.25 * float(np.median(radius[finite])) if finite.any() else 1.0
    lo = np.minimum(txy.min(axis=0), dxy.min(axis=0))
    cell = max(float(radius[radius <= ref].max(initial=0.0)), 1e-6)
    if cell < 1.0:  # cells no narrower than extent / 65536: the keys stay far below 2**63
        extent = float((np.maximum(txy.max(axis=0), dxy.max(axis=0)) - lo).max())
        cell = max(cell, extent / 65536.0)
    dc = ((dxy - lo) // cell).astype(np.int64)
    width = int(max(dc[:, 0].max(), ((txy[:, 0] - lo[0]) // cell).max())) + 3
    dkey = (dc[:, 1] + 1) * width + dc[:, 0] + 1
    order = np.argsort(dkey, kind="stable")
    narrow = (radius <= cell).nonzero()[0]
    tc = ((txy[narrow] - lo) // cell).astype(np.int64) + 1
    keys = ((tc[:, 1, None] + _NEIGHBOURS[:, 1]) * width + tc[:, 0, None] + _NEIGHBOURS[:, 0])
    keys = keys.ravel()
    n_cells = int(max(dkey.max(), keys.max(initial=0))) + 2
    if n_cells <= 8 * (keys.size + dkey.size) + 4096:  # a table of cell starts
        first = np.zeros(n_cells + 1, dtype=np.int64)
        np.cumsum(np.bincount(dkey, minlength=n_cells), out=first[1:])
        keys = np.maximum(keys, 0)
        start = first[keys]
        count = first[keys + 1] - start
    else:  # sparse extent (an outlier far away): binary search in the sorted keys
        skey = dkey[order]
        start = np.searchsorted(skey, keys, side="left")
        count = np.searchsorted(skey, keys, side="right") - start
    total = int(count.sum())
    ti = np.repeat(np.repeat(narrow, 9), count)
    # positions start[r], start[r] + 1, ... for every (track, cell) run r
    run_start = np.repeat(start - np.concatenate([[0], np.cumsum(count)[:-1]]), count)
    dj = order[run_start + np.arange(total)]
    wide = (~(radius <= cell)).nonzero()[0]
    if wide.size:
        tree = cKDTree(dxy)
        r = np.where(np.isfinite(radius[wide]), radius[wide], np.inf)
        balls = tree.query_ball_point(txy[wide], np.minimum(r, 1e12))
        counts = np.fromiter((len(b) for b in balls), dtype=np.intp, count=wide.size)
        ti = np.concatenate([ti, np.repeat(wide, counts)])
        dj = np.concatenate(
            [dj, np.fromiter((j for b in balls for j in b), dtype=np.intp,
                             count=int(counts.sum()))]
        )
    return ti.astype(np.intp), dj.astype(np.intp)


def _sorted(ti: IntArray, dj: IntArray, m: int) -> tuple[IntArray, IntArray]:
    """The pairs sorted by track, then detection (``m`` detections)."""
    order = np.argsort(ti.astype(np.int64) * m + dj, kind="stable")
    return ti[order], dj[order]


def size_factors2(wh: FloatArray, inv_ref2: float) -> FloatArray:
    """Per-axis size factors squared of the gates, ``(f_x², f_y²) = max(1, (w, h)² /
    size_ref²)`` (N, 2), ``inv_ref2 = 1 / size_ref²`` (1 for boxes without a size): a box
    larger than ``size_ref`` stretches its Euclidean gate per axis."""
    return np.fmax(wh * wh * inv_ref2, 1.0)  # fmax: NaN → 1


def r_factor(f2: FloatArray) -> FloatArray:
    """``max(f_x, f_y)²`` (N,): the factor of the measurement variance (the larger axis's,
    so that the one isotropic variance covers the noisier axis)."""
    return np.maximum(f2[:, 0], f2[:, 1])


def warmup_centre(
    pxy: FloatArray, hits: NDArray[np.int64], last_xy: FloatArray, prev_xy: FloatArray,
    last_k: NDArray[np.int64], prev_k: NDArray[np.int64], k: int, warmup_hits: int,
) -> FloatArray:
    """Paper 1's warm-up gate centre (SPEC §1.1 [R]) instead of the prediction ``pxy``.

    Until a track has ``warmup_hits`` (``2M = 6``) associations the gate centre is the linear
    extrapolation of its last two measurements, ``2 y_k − y_{k−1}`` for consecutive frames
    (scaled by the elapsed frames after misses), and ``y_k`` after a single association.
    """
    warm = hits < warmup_hits
    if not np.count_nonzero(warm):
        return pxy
    span = np.maximum(last_k - prev_k, 1)[:, None]
    gap = (k - last_k)[:, None]
    last = last_xy
    centre = last + (last - prev_xy) * (gap / span)  # 2y_k − y_{k−1}, SPEC §1.1 [R]
    return np.where(warm[:, None], centre, pxy)


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
    g = resolve_gate(dist, gate)
    det_xy, _ = det_arrays(dets)
    n, m = len(view), det_xy.shape[0]
    if method not in ("auto", "dense", "grid"):
        raise ValueError(f"candidate_pairs: unknown method {method!r}")
    if not (np.isfinite(view.xy).all() and np.isfinite(det_xy).all()):
        raise ValueError("candidate_pairs: track or detection positions contain NaN or inf")
    if method == "dense" or n * m == 0 or (method == "auto" and n * m <= DENSE_PAIRS):
        ti, dj = _all_pairs(n, m)
    else:
        radius = gate_radius(dist, view, dets, g, **params)
        ti, dj = _sorted(*spatial_pairs(view.xy, det_xy, radius), m)
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
