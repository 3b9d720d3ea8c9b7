"""The region of each track's gate, for drawing it and for searching inside it.

A gate is the set ``{z : (z − c)ᵀ C⁻¹ (z − c) ≤ r²}`` around a centre ``c``: the threshold
``r²`` is the gate on the squared distance (px² for ``euclidean``, a χ² value for the
others), the shape ``C`` says how the distance measures the offset. :func:`gate_shapes` gives
``C`` for each distance of :mod:`mvtrack.association.distances`, :func:`axis_shapes` the
axis-aligned ``C = diag(s_x, s_y)`` of a per-axis scaled Euclidean distance (the tracker's
size stretch), and :class:`GateRegions` holds the gates of a tracker's live tracks
(:meth:`mvtrack.tracking.Tracker.gates`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: the distance parameters that change the shape of a gate region (see :func:`gate_shapes`)
SHAPE_PARAMS = ("rho", "min_speed", "use_innovation")


@dataclass(frozen=True)
class GateRegions:
    """The gates of ``K`` tracks: ``(z − c)ᵀ C⁻¹ (z − c) ≤ r²``.

    Attributes
    ----------
    uid, track_id : (K,) int64
        Internal identity and public ID (−1 while tentative) of each track.
    center : (K, 2)
        Gate centres ``c``.
    shape : (K, 2, 2)
        Shape matrices ``C`` (NaN where the region is not an ellipse about the centre).
    second_shape : (K, 2, 2) or None
        Shapes of the second association stage's gates around the same centres (None
        without a second stage).
    r2 : float
        The gate on the squared distance, the same for every track.
    second_r2 : float or None
        The second stage's gate on the squared distance.
    """

    uid: IntArray
    track_id: IntArray
    center: FloatArray
    shape: FloatArray
    second_shape: FloatArray | None
    r2: float
    second_r2: float | None

    def __len__(self) -> int:
        return int(self.center.shape[0])

    def take(self, idx: NDArray[np.intp] | NDArray[np.bool_]) -> GateRegions:
        """The gates of rows ``idx`` (indices or a mask)."""
        second = None if self.second_shape is None else self.second_shape[idx]
        return GateRegions(self.uid[idx], self.track_id[idx], self.center[idx],
                           self.shape[idx], second, self.r2, self.second_r2)


def axis_shapes(scale: FloatArray | None, k: int) -> FloatArray:
    """Shapes (k, 2, 2) of a scaled Euclidean gate ``Δx²/s_x + Δy²/s_y ≤ r²``.

    ``scale``: ``None`` (a circle, ``C = I``), ``(k,)`` (``C = s I``) or ``(k, 2)``
    (``C = diag(s_x, s_y)``, an axis-aligned ellipse).
    """
    shape = np.zeros((k, 2, 2))
    if scale is None:
        shape[:, 0, 0] = shape[:, 1, 1] = 1.0
    elif scale.ndim == 1:
        shape[:, 0, 0] = shape[:, 1, 1] = scale
    else:
        shape[:, 0, 0], shape[:, 1, 1] = scale[:, 0], scale[:, 1]
    return shape


def gate_shapes(
    distance: str,
    xy: FloatArray,
    cov: FloatArray,
    S: FloatArray,
    velocity: FloatArray,
    gate: float,
    *,
    rho: float = 2.0,
    min_speed: float = 0.5,
    use_innovation: bool | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The gate region of each track as ``(centre, C, r²)``.

    Mirrors the distances of :mod:`mvtrack.association.distances`:

    - ``euclidean`` (eq. 8 of paper 2, paper 1's circular mask): ``C = I``, ``r² = gate`` (px²);
    - ``uncoupled`` (eq. 9 of paper 2): ``C = diag(P̄x, P̄y)``;
    - ``coupled`` (SPEC §2.3): ``C = R_θ diag(ρ² σ², σ²) R_θᵀ`` with σ² = (P̄x + P̄y)/2 and θ
      the direction of the predicted velocity; eq. (9)'s ellipse where ``|v̄| < min_speed``;
    - ``mahalanobis``: ``C = S`` (or P̄ when ``use_innovation`` is False).

    Other distances (``iou``, ``coupled-literal``, whose region is not an ellipse about the
    prediction, E2.7) give NaN matrices, which drawing skips.

    Parameters
    ----------
    distance : str
        Distance name.
    xy, cov, S, velocity : arrays
        Predicted positions (K, 2), P̄ (K, 2, 2), S (K, 2, 2), velocity (K, 2) px/frame.
    gate : float
        Gate on the squared distance.
    rho, min_speed, use_innovation
        As in the distance functions (``use_innovation`` defaults to False except for
        ``mahalanobis``).
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    k = xy.shape[0]
    cov = np.asarray(cov, dtype=np.float64).reshape(k, 2, 2)
    S = np.asarray(S, dtype=np.float64).reshape(k, 2, 2)
    v = np.asarray(velocity, dtype=np.float64).reshape(k, 2)
    r2 = np.full(k, float(gate))
    if use_innovation is None:
        use_innovation = distance == "mahalanobis"
    base = S if use_innovation else cov
    var = np.stack([base[:, 0, 0], base[:, 1, 1]], axis=1)
    diag = np.zeros((k, 2, 2))
    diag[:, 0, 0], diag[:, 1, 1] = var[:, 0], var[:, 1]
    if distance == "euclidean":
        shape = axis_shapes(None, k)
    elif distance == "uncoupled":
        shape = diag  # eq. (9) of paper 2
    elif distance == "coupled":
        s = np.hypot(v[:, 0], v[:, 1])
        moving = s >= min_speed
        s_safe = np.where(moving, s, 1.0)
        c, sn = v[:, 0] / s_safe, v[:, 1] / s_safe
        rot = np.stack([np.stack([c, -sn], 1), np.stack([sn, c], 1)], 1)  # columns: ∥, ⊥
        sig2 = var.mean(axis=1)  # σ⊥² = (P̄x + P̄y)/2, SPEC §2.3 [R]
        lam = np.zeros((k, 2, 2))
        lam[:, 0, 0], lam[:, 1, 1] = rho**2 * sig2, sig2
        rotated = rot @ lam @ rot.transpose(0, 2, 1)  # SPEC §2.3: R_θ diag(σ∥², σ⊥²) R_θᵀ
        shape = np.where(moving[:, None, None], rotated, diag)
    elif distance == "mahalanobis":
        shape = base.copy()
    else:
        shape = np.full((k, 2, 2), np.nan)
    return xy, shape, r2
