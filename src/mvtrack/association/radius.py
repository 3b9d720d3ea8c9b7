"""Radius bounds of the distances: the largest centre distance at which a gate can pass.

``bound(view, det_wh, gate, **params) -> (N,)`` in pixels (``inf``: no spatial bound), so
gating can pre-filter pairs spatially (:func:`mvtrack.association.gating.spatial_pairs`)
before computing the exact values. One function per distance of
:mod:`mvtrack.association.distances`, named after it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.view import TrackView

FloatArray = NDArray[np.float64]

__all__ = ["coupled", "euclidean", "iou", "lambda_max", "mahalanobis", "unbounded", "uncoupled"]


def lambda_max(m: FloatArray) -> FloatArray:
    """Largest eigenvalue of symmetric 2×2 matrices (N, 2, 2), closed form."""
    a, b, c = m[:, 0, 0], 0.5 * (m[:, 0, 1] + m[:, 1, 0]), m[:, 1, 1]
    return 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b * b)


def euclidean(view: TrackView, det_wh: FloatArray, gate: float) -> FloatArray:
    return np.full(len(view), np.sqrt(max(gate, 0.0)))


def uncoupled(
    view: TrackView, det_wh: FloatArray, gate: float, *, use_innovation: bool = False
) -> FloatArray:
    c = view.S if use_innovation else view.cov
    vmax = np.maximum(c[:, 0, 0], c[:, 1, 1])
    return np.sqrt(max(gate, 0.0) * vmax)


def coupled(
    view: TrackView,
    det_wh: FloatArray,
    gate: float,
    *,
    rho: float = 2.0,
    min_speed: float = 0.5,
    use_innovation: bool = False,
) -> FloatArray:
    c = view.S if use_innovation else view.cov
    px, py = c[:, 0, 0], c[:, 1, 1]
    moving = np.hypot(view.velocity[:, 0], view.velocity[:, 1]) >= min_speed
    var_rot = max(rho * rho, 1.0) * 0.5 * (px + py)
    return np.sqrt(max(gate, 0.0) * np.where(moving, var_rot, np.maximum(px, py)))


def mahalanobis(
    view: TrackView, det_wh: FloatArray, gate: float, *, use_innovation: bool = True
) -> FloatArray:
    m = view.S if use_innovation else view.cov
    return np.sqrt(max(gate, 0.0) * lambda_max(m))  # |Δ|² ≤ r² λmax(S)


def iou(view: TrackView, det_wh: FloatArray, gate: float) -> FloatArray:
    r"""Centre-distance bound for ``1 − IoU <= gate``, i.e. IoU >= τ = 1 − gate.

    The union is at least either box, so the overlap width o_x satisfies
    τ w_t h_t <= o_x h_t and τ w_d h_d <= o_x h_d, i.e. o_x >= τ max(w_t, w_d); with
    o_x <= (w_t + w_d)/2 − |Δx| this bounds |Δx| by (w_t + w_d)/2 − τ w_t and by
    w_t/2 + (1/2 − τ) w_d, taken at the extreme detection width; likewise for y.
    """
    if gate >= 1.0:  # every pair passes, even disjoint boxes
        return np.full(len(view), np.inf)
    tau = 1.0 - gate
    if det_wh.shape[0] == 0:
        return np.zeros(len(view))
    wmax, wmin = det_wh.max(axis=0), det_wh.min(axis=0)
    w_ext = wmax if tau <= 0.5 else wmin  # maximises (1/2 − τ) w_d
    b1 = 0.5 * (view.wh + wmax) - tau * view.wh
    b2 = 0.5 * view.wh + (0.5 - tau) * w_ext
    b = np.clip(np.minimum(b1, b2), 0.0, None)  # (N, 2): bounds on |Δx|, |Δy|
    return np.hypot(b[:, 0], b[:, 1])


def unbounded(view: TrackView, det_wh: FloatArray, gate: float, **_: Any) -> FloatArray:
    return np.full(len(view), np.inf)
