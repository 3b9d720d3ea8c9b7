"""Measurement update of the structured Kalman filter, eqs. (13)–(15) of paper 3.

The cell update (13) forms its own innovation (the part's measurement and those inferred from
its neighbours) and takes the gain and the Joseph-form covariance of
:mod:`mvtrack.filters.kalman` (:func:`~mvtrack.filters.kalman.gain`,
:func:`~mvtrack.filters.kalman.joseph`); the relation update (14) is the standard masked
:func:`mvtrack.filters.kalman.update`.
"""

from __future__ import annotations

import numpy as np

from mvtrack.filters import kalman
from mvtrack.filters.base import FloatArray
from mvtrack.filters.structured.graph import PartGraph
from mvtrack.filters.structured.params import SKFParams
from mvtrack.filters.structured.state import SKFState, SKFTerms

__all__ = ["inferred_measurements", "relation_measurement", "update"]


def _check_z_alpha(
    z: FloatArray, alpha: FloatArray, N: int, K: int
) -> tuple[FloatArray, FloatArray]:
    z = np.asarray(z, dtype=float)
    alpha = np.asarray(alpha, dtype=float)
    if z.shape != (N, K, 2):
        raise ValueError(f"z must have shape {(N, K, 2)} (objects, parts, xy), got {z.shape}")
    if alpha.shape != (N, K):
        raise ValueError(f"alpha must have shape {(N, K)} (objects, parts), got {alpha.shape}")
    if np.any(np.isnan(alpha)) or np.any((alpha < 0) | (alpha > 1)):
        raise ValueError("alpha must lie in [0, 1] (eq. (16) of paper 3)")
    # SPEC §3.3 "No match": a missing measurement means α = 1.
    missing = ~np.all(np.isfinite(z), axis=-1)
    alpha = np.where(missing, 1.0, alpha)
    return z, alpha


def relation_measurement(
    graph: PartGraph, z: FloatArray, alpha: FloatArray, pred: FloatArray
) -> FloatArray:
    """Relation measurements of eq. (15) (with m_r → m_c, E3.1), j the second end (E3.5).

    .. math::

        m_r^{ij} = \\{(1-α^j) m_c^j - (1-α^i) m_c^i\\} + \\{α^j m_c^{j-} - α^i m_c^{i-}\\}

    Parameters
    ----------
    z : (N, K, 2)
        Cell measurements (NaN where missing; their weight 1 − α is then 0).
    alpha : (N, K)
        Occlusion degrees.
    pred : (N, K, 2)
        Cell predictions m_c^{j−}.
    """
    blend = (1.0 - alpha)[..., None] * np.nan_to_num(z) + alpha[..., None] * pred
    i, j = graph.edges[:, 0], graph.edges[:, 1]
    return blend[:, j] - blend[:, i]  # eq. (15) of paper 3


def inferred_measurements(
    graph: PartGraph, z: FloatArray, offsets: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Inferred measurements of eqs. (7) and (8) for every edge (i, j), i < j.

    .. math::

        \\tilde m^{j|i} = m_c^i + m_r^{ij} \\quad (7) \\qquad
        \\tilde m^{i|j} = m_c^j - m_r^{ij} \\quad (8)

    With Δ^{ij} = m^j − m^i, the second end is inferred from the first by adding and the first
    from the second by subtracting (E3.5).

    Parameters
    ----------
    z : (N, K, 2)
        Cell measurements.
    offsets : (N, E, 2)
        Relation offsets m_r^{ij} (the prior, E3.4, or the measurement of (15)).

    Returns
    -------
    head : (N, E, 2)
        m̃ of part ``edges[e, 1]`` from part ``edges[e, 0]``.
    tail : (N, E, 2)
        m̃ of part ``edges[e, 0]`` from part ``edges[e, 1]``.
    """
    i, j = graph.edges[:, 0], graph.edges[:, 1]
    head = z[:, i] + offsets  # eq. (7) of paper 3
    tail = z[:, j] - offsets  # eq. (8) of paper 3
    return head, tail


def update(
    params: SKFParams,
    graph: PartGraph,
    state: SKFState,
    z: FloatArray,
    alpha: FloatArray,
) -> tuple[SKFState, SKFTerms]:
    """Relation updates (14)–(15), then cell updates (13), for ``N`` objects at once.

    Parameters
    ----------
    params : SKFParams
    graph : PartGraph
    state : SKFState
        Prior (after :func:`predict`).
    z : (N, K, 2)
        Part centroids m_c^j(k); NaN where a part was not matched.
    alpha : (N, K)
        Occlusion degrees α^j(k) of eq. (16); forced to 1 where ``z`` is NaN.

    Returns
    -------
    state : SKFState
        Posterior.
    terms : SKFTerms
        The 2nd and 3rd terms of (13) and the relation quantities.

    Notes
    -----
    Cell update (eq. (13) of paper 3, readings E3.2, E3.4, E3.5):

    .. math::

        s_c^{j*} = s_c^{j-} + (1-α^j) K_c^j (m_c^j - m_c^{j-})
          + \\frac{α^j}{N_j} \\sum_{i∈\\mathcal N(j)} (1-α^i) K_c^j (\\tilde m^{j|i} - m_c^{j-})

    K_c^j is the standard gain from P_c^{j−} and R_c; P_c^{j*} = (I − K_c^jH)P_c^{j−} in Joseph
    form, whatever α (E3.9) — except that a filter that received no information at all (a cell
    with α^j = 1 and no unoccluded neighbour, a relation with both ends unmatched) keeps its
    prior covariance, so a lost part's uncertainty grows while it coasts. With α ≡ 0 this is
    exactly a bank of independent Kalman filters. The relation measurement uses the *prior*
    cell predictions, so all updates in a frame are computed from the same priors.
    """
    N, K = state.xc.shape[:2]
    z, alpha = _check_z_alpha(z, alpha, N, K)
    H = params.H
    pred = state.xc[..., :2]  # m_c^{j-}, eq. (10)
    w = 1.0 - alpha  # non-occlusion weights
    z0 = np.nan_to_num(z)  # missing rows carry weight 0 below

    # (13) reads only priors (the relation prior, or (15) from the cell priors), so it can be
    # computed before (14) with the same result as the specification's order
    mr_prior = relation_measurement(graph, z, alpha, pred)

    # cells: eq. (13)
    Kc = kalman.gain(state.Pc, H, params.R_cell)  # K_c^j (N, K, n, 2)
    own_innov = w[..., None] * (z0 - pred)
    rel = state.xr[..., :2] if params.inferred == "prior" else mr_prior  # E3.4
    head, tail = inferred_measurements(graph, z0, rel)
    i, j = graph.edges[:, 0], graph.edges[:, 1]
    # (1 − α^i)(m̃^{j|i} − m_c^{j−}) per edge, for each end, then summed over edges by incidence
    c_head = w[:, i, None] * (head - pred[:, j])  # neighbour i informs j (E3.2)
    c_tail = w[:, j, None] * (tail - pred[:, i])  # neighbour j informs i
    nb_sum = np.einsum("ke,nec->nkc", graph.head, c_head) + np.einsum(
        "ke,nec->nkc", graph.tail, c_tail
    )
    nb_weight = np.einsum("ke,ne->nk", graph.head, w[:, i]) + np.einsum(
        "ke,ne->nk", graph.tail, w[:, j]
    )  # Σ_{i∈N(j)} (1 − α^i)
    if params.normalise == "count":
        norm = np.broadcast_to(graph.degree.astype(float), (N, K))
    else:
        norm = nb_weight
    scale = np.divide(alpha, norm, out=np.zeros_like(alpha), where=norm > 0)
    nb_innov = scale[..., None] * nb_sum
    term2 = (Kc @ own_innov[..., None])[..., 0]  # 2nd term of eq. (13)
    term3 = (Kc @ nb_innov[..., None])[..., 0]  # 3rd term of eq. (13)
    xc = state.xc + term2 + term3  # eq. (13) of paper 3
    # E3.9: standard Riccati recursion whatever α, except that a cell which received no
    # information at all (own weight 1 − α^j = 0 and no weighted neighbour) keeps its prior.
    cell_info = (w > 0) | ((alpha > 0) & (nb_weight > 0))
    Pc_post = kalman.joseph(state.Pc, Kc, H, params.R_cell)
    Pc = np.where(cell_info[..., None, None], Pc_post, state.Pc)

    # relations: eq. (15) measurement, eq. (14) update
    # (15) blends the cells' priors (SPEC order); option: their posteriors, after (13)
    mr = mr_prior if params.order == "relations-first" else relation_measurement(
        graph, z, alpha, xc[..., :2])
    # SPEC §3.3 "No match": the terms of an unmatched part are dropped, so a relation with an
    # unmatched end has no measurement and coasts (with α^j = 1, (15) would measure the
    # relation by its own prediction, a loop that lets the offset drift without bound).
    matched = np.all(np.isfinite(z), axis=-1)
    rel_ok = matched[:, graph.edges[:, 0]] & matched[:, graph.edges[:, 1]]
    R_rel = params.R_rel
    if params.relation_noise == "occlusion":
        # option (not in paper 3): the blend of (15) carries the information of the measured
        # fractions only, so R_r is divided by (1 − α^i)(1 − α^j)
        info = w[:, graph.edges[:, 0]] * w[:, graph.edges[:, 1]]
        rel_ok &= info > 1e-6
        R_rel = R_rel / np.maximum(info, 1e-6)[..., None, None]
    # eq. (14) of paper 3: the standard update; relations without a measurement coast
    xr, Pr = kalman.update(state.xr, state.Pr, mr, H, R_rel, mask=rel_ok)
    # our addition (not in paper 3): a coasting relation's derivatives decay geometrically, so
    # a part hidden for many frames keeps a bounded offset from its neighbours; with both ends
    # matched, by d ** α (α of the more occluded end): (15) then measures the relation by that
    # end's own prediction in proportion to α, the same loop, and α = 1 meets the unmatched case
    if params.damping_by == "alpha":
        a_rel = np.maximum(alpha[:, graph.edges[:, 0]], alpha[:, graph.edges[:, 1]])
        damp = np.where(rel_ok, params.relation_damping ** a_rel, params.relation_damping)
    else:
        damp = np.where(rel_ok, 1.0, params.relation_damping)
    xr[..., 2:] *= damp[..., None]

    terms = SKFTerms(term2, term3, mr, head, tail)
    return SKFState(xc, Pc, xr, Pr), terms
