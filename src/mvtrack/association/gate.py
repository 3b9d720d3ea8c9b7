"""The gate: which detections a track may take, at what cost, and the region to draw.

One :class:`Gate` per frame holds, for each of the ``N`` predicted tracks, a centre ``c`` and
a 2×2 covariance ``C``: a detection at ``z`` with box ``wh_d`` is a candidate of track ``i``
when

.. math::
    (z - c_i)^T C_i^{-1} (z - c_i) + w_s \\,\\lVert \\ln(wh_d / wh_i) \\rVert^2 \\le g

(:func:`mvtrack.association.pairs.quadratic_pairs` finds the pairs, the same value is their
cost). Every distance of papers 1 and 2 but two is such a quadratic form about the
prediction (:func:`shapes`):

- ``mahalanobis`` (the default): ``C = S = P̄ + R``, the filter's innovation covariance, so
  the gate opens as the prediction grows uncertain (a lost track, a new track whose velocity is
  not known yet) and closes as the filter settles; ``g`` a χ² quantile (9.21: 99 %);
- ``euclidean`` (eq. (8) of paper 2, paper 1's circular mask): ``C = I``, ``g`` in px², where
  a gate is given (paper 1's 20 px circle); a tracker without one measures the distance in
  box sizes, ``C = s² diag(w², h²)`` with ``g`` the χ² 9.21 and ``s²`` the innovation variance
  of a new track (:func:`euclidean_box_variance`), so that the gate means the same for a
  pedestrian of 40 px and a bus of 400 px, in any image and at any frame rate;
- ``uncoupled`` (eq. (9) of paper 2): ``C = diag(P̄x, P̄y)``;
- ``coupled`` (eq. (10) of paper 2 corrected, SPEC §2.3): ``C = R_θ diag(ρ² σ², σ²) R_θᵀ``,
  σ² = (P̄x + P̄y)/2, θ the direction of the predicted velocity (eq. (9)'s ellipse where the
  speed is below ``min_speed``).

``iou`` (``1 − IoU`` of the predicted and the detected box) finds its pairs among the boxes
that overlap (:func:`mvtrack.association.pairs.overlap_pairs`: a pair of disjoint boxes has
the value 1, outside any gate below 1); ``coupled-literal`` (eq. (10) as printed, not a region
about the prediction, E2.7) is given to the assignment as a cost matrix (:meth:`Gate.matrix`).
Neither is drawn.

A track held by template matching (a vehicle that stopped and faded) takes, besides, only a
detection centred in the box it stands in (:func:`mvtrack.association.assign.standing_pairs`);
its region is drawn as the gate's.

The size term (``w_s = 1 / σ_s²``, σ_s the standard deviation of the log ratio of a track's
box sizes from frame to frame) ranks and gates a pair by its box as well as its position: a
box twice as tall is another object, nearer or farther.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.distances import get_distance, resolve_gate
from mvtrack.association.pairs import BY_MATRIX, BY_OVERLAP, BY_QUADRATIC, frame_pairs
from mvtrack.association.view import TrackView
from mvtrack.registry import DISTANCES

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

__all__ = [
    "QUADRATIC",
    "SHAPE_PARAMS",
    "Gate",
    "GateRegions",
    "euclidean_box_variance",
    "shapes",
    "tracker_gate",
    "warmup_centre",
]

#: the distances whose gate is a quadratic form about the prediction
QUADRATIC = ("mahalanobis", "euclidean", "uncoupled", "coupled")
#: the distance parameters that change the shape of a gate (see :func:`shapes`)
SHAPE_PARAMS = ("rho", "min_speed", "use_innovation")


def shapes(distance: str, cov: FloatArray, S: FloatArray, velocity: FloatArray, *,
           rho: float = 2.0, min_speed: float = 0.5, use_innovation: bool | None = None,
           wh: FloatArray | None = None, box_var: float = 0.0) -> FloatArray:
    """The gate covariance ``C`` (K, 2, 2) of each track for a quadratic ``distance``.

    ``cov`` and ``S`` are the predicted position covariance P̄ and the innovation covariance
    (K, 2, 2), ``velocity`` the predicted velocity (K, 2) px/frame; ``rho``, ``min_speed`` and
    ``use_innovation`` as in :mod:`mvtrack.association.distances` (``use_innovation``
    defaults to True for ``mahalanobis`` only). ``euclidean`` is ``I`` (pixels), or with
    ``box_var = s² > 0`` and the boxes ``wh`` (K, 2), ``s² diag(w², h²)`` (box sizes). Other
    distances give NaN.
    """
    k = cov.shape[0]
    if use_innovation is None:
        use_innovation = distance == "mahalanobis"
    base = S if use_innovation else cov
    var = np.stack([base[:, 0, 0], base[:, 1, 1]], axis=1)
    diag = np.zeros((k, 2, 2))
    diag[:, 0, 0], diag[:, 1, 1] = var[:, 0], var[:, 1]
    if distance == "euclidean":
        out = np.zeros((k, 2, 2))
        if box_var > 0:
            if wh is None:
                raise ValueError("euclidean gate in box sizes: the boxes wh are needed")
            out[:, 0, 0], out[:, 1, 1] = box_var * wh[:, 0] ** 2, box_var * wh[:, 1] ** 2
            return out  # eq. (8) of paper 2 in box sizes: (Δx / w)² + (Δy / h)², over s²
        out[:, 0, 0] = out[:, 1, 1] = 1.0  # eq. (8) of paper 2
        return out
    if distance == "uncoupled":
        return diag  # eq. (9) of paper 2
    if distance == "coupled":
        if rho <= 0:
            raise ValueError(f"coupled distance: rho must be positive, got {rho}")
        s = np.hypot(velocity[:, 0], velocity[:, 1])
        moving = s >= min_speed
        s_safe = np.where(moving, s, 1.0)
        c, sn = velocity[:, 0] / s_safe, velocity[:, 1] / s_safe
        rot = np.stack([np.stack([c, -sn], 1), np.stack([sn, c], 1)], 1)  # columns: ∥, ⊥
        sig2 = var.mean(axis=1)  # σ⊥² = (P̄x + P̄y)/2, SPEC §2.3 [R]
        lam = np.zeros((k, 2, 2))
        lam[:, 0, 0], lam[:, 1, 1] = rho**2 * sig2, sig2
        rotated = rot @ lam @ rot.transpose(0, 2, 1)  # SPEC §2.3: R_θ diag(σ∥², σ⊥²) R_θᵀ
        return np.where(moving[:, None, None], rotated, diag)
    if distance == "mahalanobis":
        return np.array(base, dtype=np.float64)
    return np.full((k, 2, 2), np.nan)


def euclidean_box_variance(measurement_noise: float, velocity_prior: float,
                           accel_noise: float, fps: float) -> float:
    r"""``s²``, box sizes²: the variance of a Euclidean gate in box sizes (:func:`shapes`).

    .. math:: s^2 = 2 σ_z^2 + (σ_v / f)^2 + (σ_a / f^2)^2 / 4

    with ``σ_z`` the measurement noise (box sizes), ``σ_v`` the velocity prior (box sizes/s),
    ``σ_a`` the acceleration noise (box sizes/s²) and ``f`` the frame rate: the innovation
    variance, per axis in box sizes, of a track one frame after its first detection under the
    constant-velocity filter with the tracker's size-scaled noise (P₀ = diag(σ_z², (σ_v/f)²),
    eq. (7) of paper 1 for one frame, ``S = P̄ + R``). A Euclidean gate does not follow the
    filter's uncertainty; this one is the default's first gate of a new track, held for the
    track's whole life: in box sizes it is the same in any image, and it opens at a low frame
    rate as far as a new object may move in a frame. At 25 fps with the default noise it is
    ``s² = 0.0236``, a gate of ``√(9.21 s²) = 0.47`` box sizes.
    """
    f = float(fps)
    return float(2.0 * measurement_noise**2 + (velocity_prior / f) ** 2
                 + 0.25 * (accel_noise / f**2) ** 2)


def tracker_gate(distance: str, gate: float | None, measurement_noise: float,
                 velocity_prior: float, accel_noise: float, fps: float) -> tuple[float, float]:
    """A tracker's threshold ``g`` and Euclidean box variance ``s²`` (0: pixels).

    An explicit ``gate`` is the distance's own units (px² for ``euclidean``: paper 1's
    circle); without one, a distance with a ``box_gate`` in :data:`mvtrack.registry.DISTANCES`
    (``euclidean``: the χ² 9.21) is gated on the distance in box sizes with ``s²`` of
    :func:`euclidean_box_variance`, and every other distance takes its default
    (:func:`mvtrack.association.distances.resolve_gate`). The noise settings are those of
    :class:`mvtrack.tracking.TrackerConfig` (box sizes and seconds).
    """
    box_gate = DISTANCES[distance].box_gate if distance in DISTANCES else None
    if gate is None and box_gate is not None:
        return box_gate, euclidean_box_variance(measurement_noise, velocity_prior,
                                                accel_noise, fps)
    return resolve_gate(distance, gate), 0.0


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
    centre = last_xy + (last_xy - prev_xy) * (gap / span)  # 2y_k − y_{k−1}, SPEC §1.1 [R]
    return np.where(warm[:, None], centre, pxy)


@dataclass(frozen=True)
class GateRegions:
    """The gates of ``K`` tracks as regions to draw: ``(z − c)ᵀ C⁻¹ (z − c) ≤ r²``.

    Attributes
    ----------
    uid, track_id : (K,) int64
        Internal identity and public ID (−1 while tentative) of each track.
    center : (K, 2)
        Gate centres ``c``.
    shape : (K, 2, 2)
        Covariances ``C`` (NaN where the gate is not an ellipse about the centre).
    r2 : float
        The gate on the squared distance, the same for every track.
    """

    uid: IntArray
    track_id: IntArray
    center: FloatArray
    shape: FloatArray
    r2: float

    def __len__(self) -> int:
        return int(self.center.shape[0])

    def take(self, idx: NDArray[np.intp] | NDArray[np.bool_]) -> GateRegions:
        """The gates of rows ``idx`` (indices or a mask)."""
        return GateRegions(self.uid[idx], self.track_id[idx], self.center[idx],
                           self.shape[idx], self.r2)


@dataclass(frozen=True)
class Gate:
    """The gates of ``N`` predicted tracks for one frame.

    Attributes
    ----------
    distance : str
        The distance's name.
    view : TrackView
        The predicted tracks (centres, P̄, S, velocity, box sizes).
    threshold : float
        ``g``: pairs with a value ``<= g`` are candidates.
    cov : (N, 3) float64
        ``C`` as ``(c_xx, c_xy, c_yy)`` for the quadratic distances (NaN otherwise).
    size_weight : float
        ``w_s`` of the size term (0: none).
    params : dict
        The distance's own parameters.
    """

    distance: str
    view: TrackView
    threshold: float
    cov: FloatArray
    size_weight: float = 0.0
    params: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def build(cls, distance: str, view: TrackView, threshold: float, *,
              size_weight: float = 0.0, box_var: float = 0.0, **params: Any) -> Gate:
        """The gate of ``distance`` for the tracks of ``view`` (``box_var``: the Euclidean
        gate in box sizes, :func:`shapes`)."""
        shape_params = {p: v for p, v in params.items() if p in SHAPE_PARAMS}
        C = shapes(distance, view.cov, view.S, view.velocity, wh=view.wh, box_var=box_var,
                   **shape_params)
        cov = np.stack([C[:, 0, 0], 0.5 * (C[:, 0, 1] + C[:, 1, 0]), C[:, 1, 1]], axis=1)
        return cls(distance, view, float(threshold), np.ascontiguousarray(cov),
                   float(size_weight), dict(params))

    def __len__(self) -> int:
        return len(self.view)

    @property
    def quadratic(self) -> bool:
        """Whether the gate is a quadratic form about the prediction."""
        return self.distance in QUADRATIC

    @property
    def search(self) -> int:
        """How its pairs are found (:func:`mvtrack.association.pairs.frame_pairs`): about
        each prediction (the quadratic gates), among overlapping boxes (``iou``) or in the
        cost matrix (``coupled-literal``)."""
        if self.quadratic:
            return BY_QUADRATIC
        return BY_OVERLAP if self.distance == "iou" else BY_MATRIX

    def matrix(self, dxy: FloatArray, dwh: FloatArray) -> FloatArray:
        """The gate's value of every track and detection (N, M), the size term included.

        The reference the tests check the pair searches against, and the cost matrix of the
        gate that has no search of its own (:meth:`dense`).
        """
        n, m = len(self.view), dxy.shape[0]
        ti, dj = np.divmod(np.arange(n * m), max(m, 1))
        if self.quadratic:
            d = dxy[dj] - self.view.xy[ti]
            c = self.cov[ti]
            det = c[:, 0] * c[:, 2] - c[:, 1] ** 2
            value = (c[:, 2] * d[:, 0] ** 2 - 2 * c[:, 1] * d[:, 0] * d[:, 1]
                     + c[:, 0] * d[:, 1] ** 2) / det
        else:
            dist = get_distance(self.distance)
            value = dist.pairs(self.view, dxy, dwh, ti, dj, **self.params)
        if self.size_weight:
            lr = np.log(dwh[dj] / self.view.wh[ti])
            value = value + self.size_weight * (lr**2).sum(axis=1)
        return np.asarray(value, dtype=np.float64).reshape(n, m)

    def dense(self, dxy: FloatArray, dwh: FloatArray) -> FloatArray:
        """The cost matrix the assignment needs (:func:`mvtrack.association.assign.associate`):
        :meth:`matrix` for a gate searched in it, else an empty (0, 0) one."""
        if self.search != BY_MATRIX:
            return np.zeros((0, 0))
        return np.ascontiguousarray(self.matrix(dxy, dwh))

    def pairs(self, dxy: FloatArray, dwh: FloatArray) -> tuple[NDArray[np.intp],
                                                             NDArray[np.intp], FloatArray]:
        """The candidate pairs ``(ti, dj, value)`` of the tracks and detections at ``dxy``
        with boxes ``dwh``, sorted by track then detection (the tracker's own search,
        :mod:`mvtrack.association.assign`)."""
        n, m = len(self), dxy.shape[0]
        tsel, dsel = np.ones(n, bool), np.ones(m, bool)
        dxy = np.ascontiguousarray(dxy, dtype=np.float64)
        dwh = np.ascontiguousarray(dwh, dtype=np.float64)
        return frame_pairs(self.search, self.view.xy, self.cov, self.dense(dxy, dwh),
                           self.view.wh, tsel, dxy, dwh, dsel, self.threshold,
                           self.size_weight)

    def regions(self, uid: IntArray, track_id: IntArray) -> GateRegions:
        """The regions to draw (the position part: the size term only narrows them)."""
        shape = self.cov[:, [0, 1, 1, 2]].reshape(-1, 2, 2)  # [[xx, xy], [xy, yy]]
        return GateRegions(np.asarray(uid).copy(), np.asarray(track_id).copy(),
                           np.array(self.view.xy), shape, self.threshold)
