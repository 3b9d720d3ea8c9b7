"""Track-to-detection distances of papers 1 and 2, and the registry of their default gates.

Every distance is evaluated on *aligned pair index arrays*: track rows ``ti`` (P,) and detection
rows ``dj`` (P,) give ``P`` values, so one code path serves the dense ``N × M`` case
(:func:`distance_matrix`) and the sparse candidate pairs of :mod:`mvtrack.association.gating`.
All values are *squared* distances (``iou``: ``1 − IoU``); a pair passes the gate when its value
is ``<= gate``.

Names (``DISTANCES``):

=============== ===================================================== ==================
name            definition                                            default gate
=============== ===================================================== ==================
euclidean       eq. (8) of paper 2 (paper 1's circular mask)          400 (20 px)
uncoupled       eq. (9) of paper 2, per axis, weighted by P̄x, P̄y      9.21 (χ², 2 dof)
coupled         SPEC §2.3: innovation rotated along the velocity      9.21
coupled-literal eq. (10) of paper 2 exactly as printed (E2.3–E2.9)   9.21
mahalanobis     full innovation covariance S                          9.21
iou             1 − IoU of the boxes                                  0.7
=============== ===================================================== ==================

Each entry also gives a per-track *radius bound*: the largest centre distance in pixels at which
the gate can still pass, so gating can pre-filter pairs spatially (grid hash) before computing
the exact values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import Detections

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: χ² quantile, 2 degrees of freedom, 99 % (SPEC §2.3)
CHI2_2DOF_99 = 9.21


@dataclass(frozen=True)
class TrackView:
    """What association needs to know about ``N`` predicted tracks.

    Attributes
    ----------
    xy : (N, 2) float64
        Predicted positions (x̄, ȳ), the gate centres.
    cov : (N, 2, 2) float64
        Predicted position covariance P̄ (paper 2's P̄x, P̄y are its diagonal).
    S : (N, 2, 2) float64
        Innovation covariance S = H P̄ Hᵀ + R.
    velocity : (N, 2) float64
        Predicted velocity (v̄x, v̄y) in pixels per frame.
    wh : (N, 2) float64
        Box width and height in pixels (zeros for point targets).
    """

    xy: FloatArray
    cov: FloatArray
    S: FloatArray
    velocity: FloatArray
    wh: FloatArray

    def __post_init__(self) -> None:
        xy = np.asarray(self.xy, dtype=np.float64).reshape(-1, 2)
        n = xy.shape[0]
        shapes = {"cov": (n, 2, 2), "S": (n, 2, 2), "velocity": (n, 2), "wh": (n, 2)}
        object.__setattr__(self, "xy", xy)
        for name, shape in shapes.items():
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.shape != shape:
                raise ValueError(f"TrackView.{name} must have shape {shape}, got {arr.shape}")
            object.__setattr__(self, name, arr)

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    @classmethod
    def from_arrays(
        cls,
        xy: FloatArray,
        *,
        cov: FloatArray | float | None = None,
        S: FloatArray | float | None = None,
        velocity: FloatArray | None = None,
        wh: FloatArray | None = None,
    ) -> TrackView:
        """Build a view, broadcasting scalars: ``cov=1.0`` means P̄ = I for every track.

        Missing ``cov`` defaults to the identity, missing ``S`` to ``cov``, missing ``velocity``
        and ``wh`` to zeros.
        """
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        n = xy.shape[0]

        def _cov(value: Any, default: FloatArray) -> FloatArray:
            if value is None:
                return default
            arr = np.asarray(value, dtype=np.float64)
            if arr.ndim == 0:
                return np.broadcast_to(arr * np.eye(2), (n, 2, 2)).copy()
            return np.broadcast_to(arr, (n, 2, 2)).copy()

        cov_a = _cov(cov, np.broadcast_to(np.eye(2), (n, 2, 2)).copy())
        s_a = _cov(S, cov_a.copy())
        vel = np.zeros((n, 2)) if velocity is None else np.broadcast_to(velocity, (n, 2))
        box = np.zeros((n, 2)) if wh is None else np.broadcast_to(wh, (n, 2))
        return cls(xy, cov_a, s_a, np.array(vel, dtype=np.float64), np.array(box, np.float64))

    @classmethod
    def from_predictor(cls, predictor: Any, state: Any, wh: FloatArray) -> TrackView:
        """The view of predicted tracks from a :class:`mvtrack.filters.base.Predictor`."""
        return cls(
            predictor.position(state),
            predictor.position_cov(state),
            predictor.innovation_cov(state),
            predictor.velocity(state),
            wh,
        )


def det_arrays(dets: Detections | FloatArray) -> tuple[FloatArray, FloatArray]:
    """Centres (M, 2) and sizes (M, 2) of ``dets`` (a :class:`Detections` or an (M, 2) array)."""
    if isinstance(dets, Detections):
        return dets.xy, dets.wh
    xy = np.asarray(dets, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"dets must be Detections or an (M, 2) array, got shape {xy.shape}")
    return xy, np.zeros_like(xy)


# --------------------------------------------------------------------------------------------
# pairwise distances: f(view, det_xy, det_wh, ti, dj, **params) -> (P,)


def _innovation(view: TrackView, det_xy: FloatArray, ti: IntArray, dj: IntArray) -> FloatArray:
    return det_xy[dj] - view.xy[ti]  # Δ = z_i − (x̄, ȳ)


def _axis_variances(view: TrackView, ti: IntArray, use_innovation: bool) -> FloatArray:
    """Per-axis variances (P, 2): the diagonal of P̄ (paper 2) or of S = P̄ + R (E2.2 option)."""
    c = view.S if use_innovation else view.cov
    return np.stack([c[ti, 0, 0], c[ti, 1, 1]], axis=1)


def euclidean(
    view: TrackView, det_xy: FloatArray, det_wh: FloatArray, ti: IntArray, dj: IntArray
) -> FloatArray:
    r"""Squared Euclidean distance, eq. (8) of paper 2 (paper 1's circular mask).

    .. math:: r_i^2 = (z_{ix} - \bar x)^2 + (z_{iy} - \bar y)^2
    """
    d = _innovation(view, det_xy, ti, dj)
    return np.einsum("pi,pi->p", d, d)  # eq. (8) of paper 2


def uncoupled(
    view: TrackView,
    det_xy: FloatArray,
    det_wh: FloatArray,
    ti: IntArray,
    dj: IntArray,
    *,
    use_innovation: bool = False,
) -> FloatArray:
    r"""Per-axis probability-weighted distance, eq. (9) of paper 2.

    .. math:: r_i^2 = \frac{(z_{ix} - \bar x)^2}{\bar P_x} + \frac{(z_{iy} - \bar y)^2}{\bar P_y}

    ``use_innovation=True`` divides by the innovation variances S_xx, S_yy = P̄ + R instead
    (SPEC E2.2: gating normally uses the innovation variance).
    """
    d = _innovation(view, det_xy, ti, dj)
    var = _axis_variances(view, ti, use_innovation)
    return (d * d / var).sum(axis=1)  # eq. (9) of paper 2


def coupled(
    view: TrackView,
    det_xy: FloatArray,
    det_wh: FloatArray,
    ti: IntArray,
    dj: IntArray,
    *,
    rho: float = 2.0,
    min_speed: float = 0.5,
    use_innovation: bool = False,
) -> FloatArray:
    r"""x-y coupled confidence region of paper 2, corrected as in SPEC §2.3.

    The innovation Δ = z_i − (x̄, ȳ) is rotated into along-track and cross-track components,
    s = |v̄|:

    .. math::
        e_\parallel = \frac{\Delta_x \bar v_x + \Delta_y \bar v_y}{s},\quad
        e_\perp = \frac{-\Delta_x \bar v_y + \Delta_y \bar v_x}{s},\quad
        r_i^2 = \frac{e_\parallel^2}{\sigma_\parallel^2} + \frac{e_\perp^2}{\sigma_\perp^2}

    with σ⊥² = (P̄x + P̄y)/2 and σ∥² = ρ² σ⊥² (SPEC §2.3 [R], ρ = 2). Where s < ``min_speed``
    the direction is undefined and eq. (9) is used instead (SPEC E2.10). This replaces the
    printed eq. (10), which rotates only the measurement about the image origin and mixes
    units (errata E2.3–E2.9; see :func:`coupled_literal`). ``use_innovation=True`` uses the
    diagonal of S = P̄ + R instead of P̄. With ρ = 1 and P̄x = P̄y it equals eq. (9).
    """
    if rho <= 0:
        raise ValueError(f"coupled distance: rho must be positive, got {rho}")
    d = _innovation(view, det_xy, ti, dj)
    var = _axis_variances(view, ti, use_innovation)
    v = view.velocity[ti]
    s = np.hypot(v[:, 0], v[:, 1])
    moving = s >= min_speed
    s_safe = np.where(moving, s, 1.0)
    e_par = (d[:, 0] * v[:, 0] + d[:, 1] * v[:, 1]) / s_safe  # SPEC §2.3, along-track
    e_perp = (-d[:, 0] * v[:, 1] + d[:, 1] * v[:, 0]) / s_safe  # SPEC §2.3, cross-track
    sig_perp2 = var.mean(axis=1)  # σ⊥² = (P̄x + P̄y)/2, SPEC §2.3 [R]
    r2 = e_par**2 / (rho**2 * sig_perp2) + e_perp**2 / sig_perp2  # SPEC §2.3
    r2_eq9 = (d * d / var).sum(axis=1)  # eq. (9) fallback for s < min_speed (E2.10)
    return np.where(moving, r2, r2_eq9)


def coupled_literal(
    view: TrackView,
    det_xy: FloatArray,
    det_wh: FloatArray,
    ti: IntArray,
    dj: IntArray,
    *,
    min_speed: float = 0.5,
) -> FloatArray:
    r"""Eq. (10) of paper 2 exactly as printed — kept for the record, do not use for tracking.

    With a_i = z_ix v̄x − z_iy v̄y, b_i = z_ix v̄y − z_iy v̄x and d_i = v̄x² + v̄y²:

    .. math::
        r_i^2 = \frac{\bar x^2 + a_i^2/d_i - 2\bar x a_i/d_i}{(\bar P_x/2)^2}
              + \frac{\bar y^2 + b_i^2/d_i - 2\bar y b_i/d_i}{(\bar P_y/2)^2}

    It is wrong (SPEC E2.6–E2.9): a_i has a sign error, only the measurement is rotated (about
    the image origin), the linear terms divide by d instead of √d and the denominators are
    squared variances. It is not invariant to moving the image origin and can be negative.
    Where d_i is below ``min_speed``² (undefined, E2.10) eq. (9) is used.
    """
    z = det_xy[dj]
    c = view.xy[ti]
    v = view.velocity[ti]
    var = _axis_variances(view, ti, False)
    dd = (v * v).sum(axis=1)  # d_i = v̄x² + v̄y²
    moving = dd >= min_speed**2
    dd_safe = np.where(moving, dd, 1.0)
    a = z[:, 0] * v[:, 0] - z[:, 1] * v[:, 1]  # a_i as printed (sign error, E2.6)
    b = z[:, 0] * v[:, 1] - z[:, 1] * v[:, 0]  # b_i as printed
    num_x = c[:, 0] ** 2 + a**2 / dd_safe - 2 * c[:, 0] * a / dd_safe  # eq. (10), printed
    num_y = c[:, 1] ** 2 + b**2 / dd_safe - 2 * c[:, 1] * b / dd_safe  # eq. (10), printed
    r2 = num_x / (var[:, 0] / 2) ** 2 + num_y / (var[:, 1] / 2) ** 2  # eq. (10), printed
    delta = z - c
    return np.where(moving, r2, (delta * delta / var).sum(axis=1))


def _inv_quadratic(m: FloatArray, d: FloatArray) -> FloatArray:
    """dᵀ M⁻¹ d for a batch of symmetric 2×2 matrices ``m`` (P, 2, 2) and vectors ``d`` (P, 2)."""
    a, b, c = m[:, 0, 0], 0.5 * (m[:, 0, 1] + m[:, 1, 0]), m[:, 1, 1]
    det = a * c - b * b
    with np.errstate(divide="ignore", invalid="ignore"):
        q = (c * d[:, 0] ** 2 - 2 * b * d[:, 0] * d[:, 1] + a * d[:, 1] ** 2) / det
    return np.where(det > 0, q, np.inf)


def mahalanobis(
    view: TrackView,
    det_xy: FloatArray,
    det_wh: FloatArray,
    ti: IntArray,
    dj: IntArray,
    *,
    use_innovation: bool = True,
) -> FloatArray:
    r"""Squared Mahalanobis distance with the full innovation covariance.

    .. math:: r_i^2 = \Delta^T S^{-1} \Delta,\qquad \Delta = z_i - (\bar x, \bar y)

    Under the Gaussian model r² is χ² with 2 degrees of freedom; the default gate 9.21 keeps
    99 %. ``use_innovation=False`` uses P̄ instead of S. A singular covariance gives ``inf``.
    """
    d = _innovation(view, det_xy, ti, dj)
    m = view.S[ti] if use_innovation else view.cov[ti]
    return _inv_quadratic(m, d)


def iou_cost(
    view: TrackView, det_xy: FloatArray, det_wh: FloatArray, ti: IntArray, dj: IntArray
) -> FloatArray:
    """``1 − IoU`` of the track boxes (predicted centre, ``view.wh``) and the detection boxes.

    In [0, 1]; 1 for disjoint boxes and for two empty boxes.
    """
    c1, s1 = view.xy[ti], view.wh[ti]
    c2, s2 = det_xy[dj], det_wh[dj]
    lo = np.maximum(c1 - s1 / 2, c2 - s2 / 2)
    hi = np.minimum(c1 + s1 / 2, c2 + s2 / 2)
    inter = np.clip(hi - lo, 0.0, None).prod(axis=1)
    union = s1.prod(axis=1) + s2.prod(axis=1) - inter
    with np.errstate(divide="ignore", invalid="ignore"):
        iou = np.where(union > 0, inter / union, 0.0)
    return 1.0 - np.clip(iou, 0.0, 1.0)


# --------------------------------------------------------------------------------------------
# radius bounds: r(view, det_wh, gate, **params) -> (N,) largest centre distance that can pass


def _lambda_max(m: FloatArray) -> FloatArray:
    """Largest eigenvalue of symmetric 2×2 matrices (N, 2, 2), closed form."""
    a, b, c = m[:, 0, 0], 0.5 * (m[:, 0, 1] + m[:, 1, 0]), m[:, 1, 1]
    return 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b * b)


def _radius_euclidean(view: TrackView, det_wh: FloatArray, gate: float) -> FloatArray:
    return np.full(len(view), np.sqrt(max(gate, 0.0)))


def _radius_uncoupled(
    view: TrackView, det_wh: FloatArray, gate: float, *, use_innovation: bool = False
) -> FloatArray:
    c = view.S if use_innovation else view.cov
    vmax = np.maximum(c[:, 0, 0], c[:, 1, 1])
    return np.sqrt(max(gate, 0.0) * vmax)


def _radius_coupled(
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


def _radius_mahalanobis(
    view: TrackView, det_wh: FloatArray, gate: float, *, use_innovation: bool = True
) -> FloatArray:
    m = view.S if use_innovation else view.cov
    return np.sqrt(max(gate, 0.0) * _lambda_max(m))  # |Δ|² ≤ r² λmax(S)


def _radius_iou(view: TrackView, det_wh: FloatArray, gate: float) -> FloatArray:
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


def _radius_unbounded(view: TrackView, det_wh: FloatArray, gate: float, **_: Any) -> FloatArray:
    return np.full(len(view), np.inf)


@dataclass(frozen=True)
class Distance:
    """A registered distance.

    Attributes
    ----------
    name : str
        Registry name.
    pairs : callable
        ``pairs(view, det_xy, det_wh, ti, dj, **params) -> (P,)`` values.
    gate : float
        Default gate (pairs with value ``<= gate`` pass).
    radius : callable
        ``radius(view, det_wh, gate, **params) -> (N,)``: the largest centre distance in pixels
        at which each track's gate can still pass (``inf``: no spatial bound).
    params : tuple of str
        Keyword parameters ``pairs`` and ``radius`` accept.
    """

    name: str
    pairs: Callable[..., FloatArray]
    gate: float
    radius: Callable[..., FloatArray]
    params: tuple[str, ...] = ()


DISTANCES: dict[str, Distance] = {
    d.name: d
    for d in (
        Distance("euclidean", euclidean, 400.0, _radius_euclidean),
        Distance("uncoupled", uncoupled, CHI2_2DOF_99, _radius_uncoupled, ("use_innovation",)),
        Distance(
            "coupled",
            coupled,
            CHI2_2DOF_99,
            _radius_coupled,
            ("rho", "min_speed", "use_innovation"),
        ),
        Distance(
            "coupled-literal", coupled_literal, CHI2_2DOF_99, _radius_unbounded, ("min_speed",)
        ),
        Distance(
            "mahalanobis", mahalanobis, CHI2_2DOF_99, _radius_mahalanobis, ("use_innovation",)
        ),
        Distance("iou", iou_cost, 0.7, _radius_iou),
    )
}


def get_distance(name: str | Distance) -> Distance:
    """The registry entry for ``name`` (a :class:`Distance` is returned unchanged)."""
    if isinstance(name, Distance):
        return name
    try:
        return DISTANCES[name]
    except KeyError:
        known = ", ".join(DISTANCES)
        raise ValueError(f"unknown distance {name!r}; choose one of: {known}") from None


def default_gate(name: str | Distance) -> float:
    """Default gate of a distance (squared units; ``iou``: a cost ``1 − IoU``)."""
    return get_distance(name).gate


def _check_params(dist: Distance, params: dict[str, Any]) -> None:
    unknown = set(params) - set(dist.params)
    if unknown:
        allowed = ", ".join(dist.params) or "none"
        raise ValueError(
            f"distance {dist.name!r} got unknown parameter(s) {sorted(unknown)}; allowed: {allowed}"
        )


def pair_distance(
    name: str | Distance,
    view: TrackView,
    dets: Detections | FloatArray,
    ti: IntArray,
    dj: IntArray,
    **params: Any,
) -> FloatArray:
    """Values (P,) of distance ``name`` for the pairs ``(ti[p], dj[p])``."""
    dist = get_distance(name)
    _check_params(dist, params)
    det_xy, det_wh = det_arrays(dets)
    ti = np.asarray(ti, dtype=np.intp)
    dj = np.asarray(dj, dtype=np.intp)
    if ti.shape != dj.shape or ti.ndim != 1:
        raise ValueError(f"ti and dj must be 1-D of equal length, got {ti.shape} and {dj.shape}")
    if ti.size == 0:
        return np.zeros(0)
    return np.asarray(dist.pairs(view, det_xy, det_wh, ti, dj, **params), dtype=np.float64)


def distance_matrix(
    name: str | Distance, view: TrackView, dets: Detections | FloatArray, **params: Any
) -> FloatArray:
    """Dense (N, M) matrix of distance ``name`` (for tests, explanations and small problems)."""
    det_xy, _ = det_arrays(dets)
    n, m = len(view), det_xy.shape[0]
    ti, dj = np.divmod(np.arange(n * m, dtype=np.intp), max(m, 1))
    return pair_distance(name, view, dets, ti, dj, **params).reshape(n, m)


def gate_radius(
    name: str | Distance,
    view: TrackView,
    dets: Detections | FloatArray,
    gate: float | None = None,
    **params: Any,
) -> FloatArray:
    """Per-track radius bound (N,) in pixels: beyond it distance ``name`` exceeds ``gate``."""
    dist = get_distance(name)
    _check_params(dist, params)
    _, det_wh = det_arrays(dets)
    g = dist.gate if gate is None else float(gate)
    return np.asarray(dist.radius(view, det_wh, g, **params), dtype=np.float64)
