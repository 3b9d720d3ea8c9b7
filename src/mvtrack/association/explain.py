"""Why was a detection not associated? Nearest track, its distance and the gate, for tuning.

:func:`explain` reports, for each unassociated detection (or the ones asked for), the nearest
track by the chosen distance, that value and the gate, and for each track left without a
detection the nearest detection. ``Explanation.table()`` renders it as a small text table.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from mvtrack.association.assign import Assignment, assign
from mvtrack.association.distances import (
    Distance,
    FloatArray,
    IntArray,
    TrackView,
    det_arrays,
    get_distance,
    pair_distance,
    resolve_gate,
)
from mvtrack.association.gate import Gate
from mvtrack.types import Detections

#: evaluate nearest-neighbour distances in blocks of at most this many pairs
_BLOCK = 1 << 20


@dataclass(frozen=True)
class Explanation:
    """Nearest counterparts of unassociated detections and tracks.

    Attributes
    ----------
    distance : str
        Distance name.
    gate : float
        The gate (pairs pass when value ``<= gate``).
    det : (k,) intp
        Detection rows explained.
    det_track : (k,) intp
        Nearest track of each (``-1`` when there are no tracks).
    det_value : (k,) float64
        Its distance value (``inf`` when there are no tracks).
    det_assigned_track : (k,) intp
        The track the detection went to (``-1``: none).
    track : (l,) intp
        Track rows explained (tracks without a detection by default).
    track_det : (l,) intp
        Nearest detection of each (``-1`` when there are none).
    track_value : (l,) float64
        Its distance value.
    """

    distance: str
    gate: float
    det: IntArray
    det_track: IntArray
    det_value: FloatArray
    det_assigned_track: IntArray
    track: IntArray
    track_det: IntArray
    track_value: FloatArray

    @property
    def det_reason(self) -> list[str]:
        """One phrase per explained detection."""
        out = []
        for trk, val, got in zip(
            self.det_track, self.det_value, self.det_assigned_track, strict=True
        ):
            if got >= 0:
                out.append(f"associated with track {got}")
            elif trk < 0:
                out.append("no tracks")
            elif not val <= self.gate:
                out.append(f"outside gate: {val:.4g} > {self.gate:.4g}")
            else:
                out.append("inside a gate, but every gating track took another detection")
        return out

    def table(self) -> str:
        """A plain-text table of the explanation."""
        lines = [f"distance {self.distance}, gate {self.gate:.4g}", "detection  nearest  value"]
        for d, t, v, why in zip(
            self.det, self.det_track, self.det_value, self.det_reason, strict=True
        ):
            lines.append(f"{d:9d}  {t:7d}  {v:10.4g}  {why}")
        lines.append("track  nearest-det  value")
        for t, d, v in zip(self.track, self.track_det, self.track_value, strict=True):
            lines.append(f"{t:5d}  {d:11d}  {v:10.4g}")
        return "\n".join(lines)


def _nearest(
    dist: Distance,
    view: TrackView,
    dets: Detections | FloatArray,
    rows: IntArray,
    by_track: bool,
    params: dict[str, Any],
) -> tuple[IntArray, FloatArray]:
    """Nearest counterpart (and value) of each of ``rows`` among all tracks or detections."""
    n_other = det_arrays(dets)[0].shape[0] if by_track else len(view)
    k = rows.shape[0]
    best = np.full(k, -1, dtype=np.intp)
    value = np.full(k, np.inf)
    if k == 0 or n_other == 0:
        return best, value
    step = max(1, _BLOCK // n_other)
    for s in range(0, k, step):  # blocks of rows, each fully vectorised
        r = rows[s : s + step]
        own = np.repeat(r, n_other)
        other = np.tile(np.arange(n_other, dtype=np.intp), r.shape[0])
        ti, dj = (own, other) if by_track else (other, own)
        v = pair_distance(dist, view, dets, ti, dj, **params).reshape(r.shape[0], n_other)
        v = np.where(np.isnan(v), np.inf, v)
        j = np.argmin(v, axis=1)
        best[s : s + step] = j
        value[s : s + step] = v[np.arange(r.shape[0]), j]
    return best, value


def explain(
    view: TrackView,
    dets: Detections | FloatArray,
    distance: str | Distance = "euclidean",
    gate: float | None = None,
    *,
    assignment: Assignment | None = None,
    rule: Literal["nearest", "greedy", "optimal"] = "optimal",
    det: int | IntArray | None = None,
    track: int | IntArray | None = None,
    **params: Any,
) -> Explanation:
    """Explain the association of one frame.

    Parameters
    ----------
    view, dets, distance, gate, **params
        The tracks, the detections, the distance, its gate and parameters
        (:class:`mvtrack.association.gate.Gate`).
    assignment : Assignment, optional
        The frame's assignment; computed with ``rule`` when omitted.
    det : int or int array, optional
        Detection rows to explain (default: the unassociated ones).
    track : int or int array, optional
        Track rows to explain (default: the ones without a detection).

    Returns
    -------
    Explanation
    """
    dist = get_distance(distance)
    g = resolve_gate(dist, gate)
    n, m = len(view), det_arrays(dets)[0].shape[0]
    if assignment is None:
        dxy, dwh = det_arrays(dets)
        ti, dj, cost = Gate.build(dist.name, view, g, **params).pairs(dxy, dwh)
        assignment = assign(ti, dj, cost, n, m, rule, unmatched_cost=g)
    det_rows = assignment.unmatched_dets if det is None else np.atleast_1d(det).astype(np.intp)
    trk_rows = (
        assignment.unmatched_tracks if track is None else np.atleast_1d(track).astype(np.intp)
    )
    if det_rows.size and (det_rows.min() < 0 or det_rows.max() >= m):
        raise ValueError(f"explain: detection row out of range [0, {m})")
    if trk_rows.size and (trk_rows.min() < 0 or trk_rows.max() >= n):
        raise ValueError(f"explain: track row out of range [0, {n})")
    d_trk, d_val = _nearest(dist, view, dets, det_rows, False, params)
    t_det, t_val = _nearest(dist, view, dets, trk_rows, True, params)
    # the track each explained detection went to (the lowest track row if shared)
    owner = np.full(m, n, dtype=np.intp)
    np.minimum.at(owner, assignment.det, assignment.track)
    owner[owner == n] = -1
    return Explanation(
        dist.name, g, det_rows, d_trk, d_val, owner[det_rows], trk_rows, t_det, t_val
    )
