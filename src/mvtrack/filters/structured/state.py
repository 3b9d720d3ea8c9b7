"""State of the structured Kalman filter: start, time update (eqs. (9)–(12)), new parts.

Cells and relations are two batches of linear Kalman filters with leading dimensions
``(N, K)`` and ``(N, E)``; their time update is :func:`mvtrack.filters.kalman.predict`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.filters import kalman
from mvtrack.filters.base import FloatArray
from mvtrack.filters.structured.graph import PartGraph
from mvtrack.filters.structured.params import SKFParams

__all__ = ["SKFState", "SKFTerms", "add_part", "init", "predict"]


@dataclass
class SKFState:
    """State of ``N`` structured objects sharing one :class:`PartGraph`.

    Attributes
    ----------
    xc : (N, K, n)
        Cell states s_c^j (position first).
    Pc : (N, K, n, n)
        Cell covariances.
    xr : (N, E, n)
        Relation states s_r^{ij} (offset m^j − m^i first, i < j).
    Pr : (N, E, n, n)
        Relation covariances.
    """

    xc: FloatArray
    Pc: FloatArray
    xr: FloatArray
    Pr: FloatArray

    @property
    def positions(self) -> FloatArray:
        """Cell positions (N, K, 2)."""
        return self.xc[..., :2]

    @property
    def offsets(self) -> FloatArray:
        """Relation offsets m^j − m^i (N, E, 2)."""
        return self.xr[..., :2]


@dataclass
class SKFTerms:
    """Intermediate quantities of one :func:`update`, for plots and tests (Fig. 10).

    Attributes
    ----------
    own : (N, K, n)
        The 2nd term of (13), (1 − α^j) K_c^j (m_c^j − m_c^{j−}).
    neighbours : (N, K, n)
        The 3rd term of (13), α^j (1/N_j) Σ_i (1 − α^i) K_c^j (m̃^{j|i} − m_c^{j−}).
    relation_z : (N, E, 2)
        Relation measurements m_r^{ij} of (15).
    inferred_head, inferred_tail : (N, E, 2)
        m̃ for the second end of each edge inferred from the first (7), and for the first end
        inferred from the second (8).
    """

    own: FloatArray
    neighbours: FloatArray
    relation_z: FloatArray
    inferred_head: FloatArray
    inferred_tail: FloatArray


def init(params: SKFParams, graph: PartGraph, z: FloatArray) -> SKFState:
    """Filters for ``N`` new objects whose parts were first measured at ``z`` (N, K, 2).

    Cells start at their measurement, relations at the measured offsets m^j − m^i, with zero
    derivatives and P(0) = diag(R, p0_vel·I₂, p0_acc·I₂) (SPEC §3.3).
    """
    z = np.asarray(z, dtype=float)
    if z.ndim != 3 or z.shape[1:] != (graph.n_parts, 2):
        raise ValueError(f"z must have shape (N, {graph.n_parts}, 2), got {z.shape}")
    if not np.all(np.isfinite(z)):
        raise ValueError("every part needs a finite first measurement to start its filter")
    N, K, n = z.shape[0], graph.n_parts, params.n
    xc = np.zeros((N, K, n))
    xc[..., :2] = z
    xr = np.zeros((N, graph.n_edges, n))
    xr[..., :2] = z[:, graph.edges[:, 1]] - z[:, graph.edges[:, 0]]  # eq. (5), E3.5
    Pc = np.broadcast_to(params.P0(params.r_cell), (N, K, n, n)).copy()
    Pr = np.broadcast_to(params.P0(params.R_rel[0, 0]), (N, graph.n_edges, n, n)).copy()
    return SKFState(xc, Pc, xr, Pr)


def predict(params: SKFParams, state: SKFState) -> SKFState:
    """Predict every cell and relation filter one frame, eqs. (9)–(12) of paper 3."""
    F = params.F
    xc, Pc = kalman.predict(state.xc, state.Pc, F, params.Q)  # eqs. (9), (10) of paper 3
    xr, Pr = kalman.predict(state.xr, state.Pr, F, params.Q_rel)  # eqs. (11), (12)
    return SKFState(xc, Pc, xr, Pr)


def add_part(
    params: SKFParams,
    graph: PartGraph,
    state: SKFState,
    xy: FloatArray,
    neighbours: list[int],
) -> tuple[PartGraph, SKFState]:
    """Grow the graph by a new part first seen at ``xy`` (N, 2), adjacent to ``neighbours``.

    The new cell starts at ``xy``; each new relation starts at the offset between ``xy`` and the
    neighbour's current estimate, both with P(0) (SPEC §3.3). The new part gets index K.
    """
    xy = np.asarray(xy, dtype=float)
    N, K, n = state.xc.shape
    if xy.shape != (N, 2) or not np.all(np.isfinite(xy)):
        raise ValueError(f"xy must be finite with shape {(N, 2)}, got {xy.shape}")
    nb = sorted(set(int(v) for v in neighbours))
    if any(v < 0 or v >= K for v in nb):
        raise ValueError(f"neighbours must index existing parts 0..{K - 1}, got {neighbours}")
    new_graph = PartGraph(K + 1, np.concatenate([graph.edges, [[v, K] for v in nb]]).reshape(-1, 2))
    cell = np.zeros((N, 1, n))
    cell[:, 0, :2] = xy
    rel = np.zeros((N, len(nb), n))
    rel[..., :2] = xy[:, None, :] - state.xc[:, nb, :2]  # eq. (5): m^K − m^i, i < K
    Pc0 = np.broadcast_to(params.P0(params.r_cell), (N, 1, n, n))
    Pr0 = np.broadcast_to(params.P0(params.R_rel[0, 0]), (N, len(nb), n, n))
    new_state = SKFState(
        np.concatenate([state.xc, cell], axis=1),
        np.concatenate([state.Pc, Pc0], axis=1),
        np.concatenate([state.xr, rel], axis=1),
        np.concatenate([state.Pr, Pr0], axis=1),
    )
    return new_graph, new_state
