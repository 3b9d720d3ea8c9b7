"""The gates drawn over the video: the regions the next frame's detections must fall in."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def next_gates(
    tracker: Any, next_k: int
) -> tuple[NDArray[np.int64], FloatArray, FloatArray, FloatArray]:
    """The gates that the next frame's detections must fall in, for the confirmed tracks.

    The tracker's current predictor state is advanced one frame (a pure function of the
    state; the tracker is not changed) and turned into the region of the configured distance
    (:func:`mvtrack.viz.annotate.gate_shapes`). Under paper 1's warm-up the gate centre is
    ``2 y_k − y_{k−1}`` (SPEC §1.1 [R]) as in the tracker.

    Parameters
    ----------
    tracker : mvtrack.tracking.Tracker
        The tracker after its step for frame ``next_k − 1``.
    next_k : int
        The tracker's step number of the next frame (frames are counted from 0).

    Returns
    -------
    track_id : (K,) int64
        Public IDs of the tracks (tentative tracks are left out).
    center : (K, 2)
        Gate centres.
    shape : (K, 2, 2)
        Shape matrices ``C`` of ``(z − c)ᵀ C⁻¹ (z − c) ≤ r²``.
    r2 : (K,)
        Gate thresholds.
    """
    from mvtrack.association.distances import get_distance
    from mvtrack.viz.annotate import gate_shapes

    tab = tracker.tracks
    keep = np.asarray(tab.track_id) > 0
    if not keep.any():
        z = np.zeros(0)
        return z.astype(np.int64), z.reshape(0, 2), z.reshape(0, 2, 2), z
    from mvtrack import _batch

    pred = tracker.predictor
    ps = pred.predict(_batch.take(tracker.pstate, keep))
    xy = pred.position(ps)
    config = tracker.config
    fp = config.frames()
    if fp.warmup_hits:
        warm = tab.hits[keep] < fp.warmup_hits
        last, prev = tab.last_xy[keep], tab.prev_xy[keep]
        span = np.maximum(tab.last_k[keep] - tab.prev_k[keep], 1)[:, None]
        gap = (next_k - tab.last_k[keep])[:, None]
        centre = last + (last - prev) * (gap / span)  # 2 y_k − y_{k−1}, SPEC §1.1 [R]
        xy = np.where(warm[:, None], centre, xy)
    dist = get_distance(config.distance)
    gate = dist.gate if config.gate is None else float(config.gate)
    params = {k: v for k, v in dict(getattr(config, "distance_params", {})).items()
              if k in ("rho", "min_speed", "use_innovation")}
    center, shape, r2 = gate_shapes(
        config.distance, xy, pred.position_cov(ps), pred.innovation_cov(ps), pred.velocity(ps),
        gate, **params,
    )
    return np.asarray(tab.track_id)[keep], center, shape, r2


def second_gates(tracker: Any, next_k: int) -> tuple[FloatArray, FloatArray] | None:
    """The second association stage's circles for the next frame, or None without one.

    Tracks the first stage leaves unmatched may take a leftover detection within
    ``config.second_gate`` px of the same gate centre (gated global nearest neighbour, see
    :class:`~mvtrack.tracking.Tracker`). Returns the centres (K, 2) and radii² (K,) for the
    confirmed tracks, in the order of :func:`next_gates`. (The recovery stage, around the last
    measurement of established tracks, is not drawn.)
    """
    radius = getattr(tracker.config, "second_gate", None)
    if radius is None:
        return None
    _, center, _, _ = next_gates(tracker, next_k)
    return center, np.full(center.shape[0], float(radius) ** 2)
