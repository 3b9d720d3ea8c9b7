"""Track-to-detection distances of papers 1 and 2, by name.

Every distance is evaluated on *aligned pair index arrays*: track rows ``ti`` (P,) and detection
rows ``dj`` (P,) give ``P`` values, so one code path serves the dense ``N × M`` case
(:func:`distance_matrix`) and the sparse candidate pairs of :mod:`mvtrack.association.gating`.
All values are *squared* distances (``iou``: ``1 − IoU``); a pair passes the gate when its value
is ``<= gate``.

Names (``DISTANCES``):

=============== ===================================================== ==================
name            definition                                            default gate
=============== ===================================================== ==================
euclidean       eq. (8) of paper 2 (paper 1's circular mask)          100 (10 px)
uncoupled       eq. (9) of paper 2, per axis, weighted by P̄x, P̄y      9.21 (χ², 2 dof)
coupled         SPEC §2.3: innovation rotated along the velocity      9.21
coupled-literal eq. (10) of paper 2 exactly as printed (E2.3–E2.9)   9.21
mahalanobis     full innovation covariance S                          9.21
iou             1 − IoU of the boxes                                  0.7
=============== ===================================================== ==================

The names, their help and their default gates are :data:`mvtrack.registry.DISTANCES` (the one
table of default gates; :func:`resolve_gate` applies it). The tracker does not call these
functions pair by pair: the quadratic ones are its gate's covariance
(:mod:`mvtrack.association.gate`, tested equal to them), the others its cost matrix.
:class:`TrackView` is :mod:`mvtrack.association.view`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack import registry
from mvtrack.association.view import TrackView, det_arrays
from mvtrack.registry import CHI2_2DOF_99
from mvtrack.types import Detections

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

__all__ = [
    "CHI2_2DOF_99",
    "DISTANCES",
    "Distance",
    "TrackView",
    "coupled",
    "coupled_literal",
    "default_gate",
    "det_arrays",
    "distance_matrix",
    "euclidean",
    "get_distance",
    "iou_cost",
    "mahalanobis",
    "pair_distance",
    "resolve_gate",
    "uncoupled",
]


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
    params : tuple of str
        Keyword parameters ``pairs`` accepts.
    """

    name: str
    pairs: Callable[..., FloatArray]
    gate: float
    params: tuple[str, ...] = ()


def _registered(
    name: str, pairs: Callable[..., FloatArray], params: tuple[str, ...] = ()
) -> Distance:
    """The distance ``name`` of :data:`mvtrack.registry.DISTANCES`, with its default gate."""
    return Distance(name, pairs, registry.default_gate(name), params)


#: the registered distances by name (names, help and default gates:
#: :data:`mvtrack.registry.DISTANCES`)
DISTANCES: dict[str, Distance] = {
    d.name: d
    for d in (
        _registered("euclidean", euclidean),
        _registered("uncoupled", uncoupled, ("use_innovation",)),
        _registered("coupled", coupled, ("rho", "min_speed", "use_innovation")),
        _registered("coupled-literal", coupled_literal, ("min_speed",)),
        _registered("mahalanobis", mahalanobis, ("use_innovation",)),
        _registered("iou", iou_cost),
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
    """Default gate of a distance (squared units; ``iou``: a cost ``1 − IoU``).

    Registered distances take theirs from :data:`mvtrack.registry.DISTANCES`; a
    :class:`Distance` object carries its own.
    """
    return get_distance(name).gate


def resolve_gate(distance: str | Distance, gate: float | None = None) -> float:
    """The gate applied with ``distance``: ``gate`` if given, else the distance's default.

    The one place where a missing gate becomes a number (the tracker, gating, explanations,
    radius bounds and the video settings all call it).

    Parameters
    ----------
    distance : str or Distance
        A registered name or a :class:`Distance`.
    gate : float or None
        An explicit gate (squared units; ``iou``: a cost ``1 − IoU``), or None.

    Returns
    -------
    float
    """
    return default_gate(distance) if gate is None else float(gate)


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
