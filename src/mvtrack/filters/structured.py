"""The structured Kalman filter (SKF) of paper 3 (SPEC §3), batched over objects and parts.

An object is a set of ``K`` parts (regions of one colour, e.g. head, torso, legs) joined by an
adjacency graph with ``E`` edges (:class:`PartGraph`). Every part has a *cell* Kalman filter on
its centre m_c^j; every adjacent pair (i, j), stored with i < j, has a *relation* Kalman filter on
the offset m_r^{ij} = m^j − m^i (eq. (5) of paper 3, E3.5). When a part is occluded (its
occlusion degree α^j of eq. (16) is high) its update leans on the measurements of its neighbours
carried over by the relation filters:

.. math::

    s_c^{j*} = s_c^{j-} + (1-α^j) K_c^j (m_c^j - m_c^{j-})
             + \\frac{α^j}{N_j} \\sum_{i∈\\mathcal N(j)} (1-α^i) K_c^j (\\tilde m^{j|i} - m_c^{j-})
    \\qquad (13)

    s_r^{ij*} = s_r^{ij-} + K_r^{ij} (m_r^{ij} - m_r^{ij-}) \\qquad (14)

    m_r^{ij} = \\{(1-α^j) m_c^j - (1-α^i) m_c^i\\} + \\{α^j m_c^{j-} - α^i m_c^{i-}\\} \\qquad (15)

with the readings of SPEC §4: the inner weight is the neighbour's (1 − α^i) (E3.2); the inferred
measurement is m̃^{j|i} = m_c^i + m_r^{ij−} from the relation *prior* (E3.4; option
``inferred="measurement"`` uses the relation measurement of (15), the literal (7)); the sign of
the relation follows its orientation (E3.5: j from i adds, i from j subtracts); the state is 6-D
constant acceleration with Δt²/2 (E3.7; option ``model="cv"``, 4-D, E3.6); the covariance follows
the standard Riccati recursion, independent of α (E3.9).

All state lives in arrays: cells ``(N, K, n)``, relations ``(N, E, n)`` for ``N`` objects that
share one part graph. The sum over neighbours in (13) is a product with the graph's incidence
matrices; there is no Python loop over objects or parts in :func:`predict` / :func:`update`.

Objects whose parts are missing in a frame get α = 1 for those parts (SPEC §3.3 "No match") and
NaN measurements; their (1 − α) terms are dropped.

Where we go beyond paper 3 (each documented on the implementing line):

- a relation with an unmatched end gets no update (with α^j = 1, (15) would measure the offset
  by the part's own prediction) and its derivatives decay by ``relation_damping`` per frame,
  so a part hidden for many frames keeps a bounded offset;
- a filter that receives no information at all keeps its prior covariance (E3.9 otherwise);
- options ``q_rel`` (relation process noise, default Q_r = 0.01·Q_c, E3.12: the parts of one
  body keep their relative positions far more steadily than the body moves; with Q_r = Q_c the
  CA relations of the X9 scene learn the legs' swing and extrapolate it while the legs are
  hidden, see the ``occlusion`` experiment) and ``relation_noise="occlusion"`` (R_r scaled by
  1/((1 − α^i)(1 − α^j))), and ``order="cells-first"`` ((13) before (15), which then blends
  the cells' posteriors instead of their priors; not the specification's order).

For the tracker, :class:`StructuredPredictor` (name ``structured``, built by
``mvtrack.filters.predictors.make_predictor("structured")``) wraps the SKF behind the
:class:`~mvtrack.filters.base.Predictor` protocol: the object position is the mean of its parts;
whole-object detections move the rigid part layout, and per-part measurements with α go through
:meth:`StructuredPredictor.update_parts`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

__all__ = [
    "PartGraph",
    "SKFParams",
    "SKFState",
    "SKFTerms",
    "StructuredKalmanFilter",
    "StructuredPredictor",
    "StructuredPredictorState",
    "add_part",
    "inferred_measurements",
    "init",
    "kf_predict",
    "kf_update",
    "predict",
    "relation_measurement",
    "search_region",
    "update",
]


# --------------------------------------------------------------------------- graph


@dataclass(frozen=True, eq=False)
class PartGraph:
    """Adjacency graph of the ``K`` parts of an object (Fig. 2 / Fig. 8 of paper 3).

    Parameters
    ----------
    n_parts : int
        Number of parts ``K`` (cells), numbered 0 … K−1.
    edges : array (E, 2) of int
        Adjacent pairs. Each pair is stored ordered, ``i < j`` (E3.5); the relation filter of
        edge ``e`` estimates ``m^{edges[e,1]} − m^{edges[e,0]}``. Use :meth:`from_edges` to build
        a graph from pairs in any orientation.
    """

    n_parts: int
    edges: IntArray

    def __post_init__(self) -> None:
        edges = np.asarray(self.edges, dtype=np.intp).reshape(-1, 2)
        if self.n_parts < 1:
            raise ValueError(f"n_parts must be >= 1, got {self.n_parts}")
        if edges.size and (edges.min() < 0 or edges.max() >= self.n_parts):
            raise ValueError(f"edges must index parts 0..{self.n_parts - 1}, got {edges.tolist()}")
        if np.any(edges[:, 0] >= edges[:, 1]):
            raise ValueError("edges must be ordered pairs i < j; use PartGraph.from_edges")
        if len({tuple(e) for e in edges.tolist()}) != len(edges):
            raise ValueError(f"duplicate edges in {edges.tolist()}")
        object.__setattr__(self, "edges", edges)

    @classmethod
    def from_edges(cls, n_parts: int, pairs: object) -> PartGraph:
        """Graph from adjacent pairs in any orientation; each is stored as (min, max)."""
        arr = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
        if np.any(arr[:, 0] == arr[:, 1]):
            raise ValueError(f"a part cannot be adjacent to itself: {arr.tolist()}")
        arr = np.sort(arr, axis=1)
        _, first = np.unique(arr, axis=0, return_index=True)
        return cls(n_parts, arr[np.sort(first)])

    @classmethod
    def chain(cls, n_parts: int) -> PartGraph:
        """The chain 0–1–2–…, e.g. head–torso–legs (Fig. 8 of paper 3)."""
        idx = np.arange(n_parts - 1)
        return cls(n_parts, np.stack([idx, idx + 1], axis=1))

    @property
    def n_edges(self) -> int:
        """Number of relations ``E``."""
        return int(self.edges.shape[0])

    @property
    def tail(self) -> FloatArray:
        """Incidence matrix (K, E): 1 where part k is the first (smaller) end of edge e."""
        out = np.zeros((self.n_parts, self.n_edges))
        out[self.edges[:, 0], np.arange(self.n_edges)] = 1.0
        return out

    @property
    def head(self) -> FloatArray:
        """Incidence matrix (K, E): 1 where part k is the second (larger) end of edge e."""
        out = np.zeros((self.n_parts, self.n_edges))
        out[self.edges[:, 1], np.arange(self.n_edges)] = 1.0
        return out

    @property
    def degree(self) -> IntArray:
        """N_j = |𝒩(j)|, the number of parts adjacent to each part (K,)."""
        return np.bincount(self.edges.ravel(), minlength=self.n_parts).astype(np.intp)

    def neighbours(self, j: int) -> list[int]:
        """Parts adjacent to part ``j``, ascending."""
        e = self.edges
        return sorted(e[e[:, 0] == j, 1].tolist() + e[e[:, 1] == j, 0].tolist())

    def filters_used_by(self, j: int, labels: list[str] | None = None) -> list[str]:
        """Names of the filters that enter part ``j``'s estimate in eq. (13): its own cell filter,
        the cell filters of its neighbours (through their measurements m_c^i) and the relation
        filters of its edges. Parts are named ``labels`` (default 1-based numbers, as in Fig. 2)."""
        names = labels or [str(k + 1) for k in range(self.n_parts)]
        cells = sorted([j, *self.neighbours(j)])
        rels = [e for e in self.edges.tolist() if j in e]
        return [f"KF{names[c]}" for c in cells] + [f"KF{names[a]}{names[b]}" for a, b in rels]


# --------------------------------------------------------------------------- parameters


@dataclass(frozen=True)
class SKFParams:
    """Parameters of the SKF (SPEC §3.3 defaults, all [R] except the model structure).

    Parameters
    ----------
    model : {"ca", "cv"}
        ``"ca"``: 6-D state [x, y, ẋ, ẏ, ẍ, ÿ] with eq. (17) corrected to Δt²/2 (E3.7);
        ``"cv"``: 4-D [x, y, ẋ, ẏ] (E3.6).
    dt : float
        Frame interval Δt (frames).
    q : float
        Process noise: Q = q·diag(0, 0, 0, 0, 1, 1) (CA) or q·diag(0, 0, 1, 1) (CV).
    q_rel : float or None
        Process noise of the relation filters (same form); ``None`` means ``0.01·q``, Q_r =
        0.01·Q_c (SPEC §3.3, E3.12). ``q_rel=q`` is the first reconstruction's Q_r = Q_c.
    r_cell : float
        Cell measurement variance, R_c = r_cell·I₂ (px²).
    r_rel : float or None
        Relation measurement variance, R_r = r_rel·I₂; ``None`` means 2·r_cell.
    p0_vel, p0_acc : float
        Initial variances of velocity and acceleration: P(0) = diag(R, p0_vel·I₂, p0_acc·I₂).
    inferred : {"prior", "measurement"}
        Relation term used in the inferred measurement m̃^{j|i} (E3.4).
    normalise : {"count", "weights"}
        Normalisation of the neighbour sum of (13): 1/N_j, or 1/Σ(1 − α^i) (E3.2).
    relation_damping : float
        Factor in [0, 1] applied each frame to the velocity and acceleration of a relation with
        an unmatched end (which coasts, having no measurement). Not in paper 3: with 1.0 a CA
        relation coasting for many frames drifts quadratically; 0.8 bounds the drift.
    relation_noise : {"constant", "occlusion"}
        ``"constant"``: R_r for every relation update (SPEC §3.3, E3.9). ``"occlusion"`` (not
        in paper 3): R_r / ((1 − α^i)(1 − α^j)), so an occluded part's own prediction, which
        (15) mixes into the relation measurement, cannot drag the learned offset along.
    order : {"relations-first", "cells-first"}
        ``"relations-first"``: the relation measurements (15) blend in the cells' *priors*
        m_c^{j−} and (14) runs before (13), as SPEC §3.1 step 5 orders them.
        ``"cells-first"`` (not the specification's): (13) first, then (15) with the cells'
        *posteriors* in place of m_c^{j−}.
    """

    model: Literal["ca", "cv"] = "ca"
    dt: float = 1.0
    q: float = 0.05
    q_rel: float | None = None
    r_cell: float = 4.0
    r_rel: float | None = None
    p0_vel: float = 25.0
    p0_acc: float = 1.0
    inferred: Literal["prior", "measurement"] = "prior"
    normalise: Literal["count", "weights"] = "count"
    relation_damping: float = 0.8
    relation_noise: Literal["constant", "occlusion"] = "constant"
    order: Literal["relations-first", "cells-first"] = "relations-first"

    def __post_init__(self) -> None:
        if self.model not in ("ca", "cv"):
            raise ValueError(f"model must be 'ca' or 'cv', got {self.model!r}")
        if self.inferred not in ("prior", "measurement"):
            raise ValueError(f"inferred must be 'prior' or 'measurement', got {self.inferred!r}")
        if self.normalise not in ("count", "weights"):
            raise ValueError(f"normalise must be 'count' or 'weights', got {self.normalise!r}")
        for name in ("dt", "r_cell", "p0_vel"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.q < 0 or self.p0_acc < 0 or (self.q_rel is not None and self.q_rel < 0):
            raise ValueError("q, q_rel and p0_acc must be >= 0")
        if self.relation_noise not in ("constant", "occlusion"):
            raise ValueError(
                f"relation_noise must be 'constant' or 'occlusion', got {self.relation_noise!r}"
            )
        if self.order not in ("relations-first", "cells-first"):
            raise ValueError(
                f"order must be 'relations-first' or 'cells-first', got {self.order!r}"
            )
        if not 0.0 <= self.relation_damping <= 1.0:
            raise ValueError(f"relation_damping must be in [0, 1], got {self.relation_damping}")
        if self.r_rel is not None and not self.r_rel > 0:
            raise ValueError(f"r_rel must be > 0, got {self.r_rel}")

    @property
    def n(self) -> int:
        """State dimension (6 for CA, 4 for CV)."""
        return 6 if self.model == "ca" else 4

    @property
    def F(self) -> FloatArray:
        """Transition matrix Φ, eq. (17) with Δt²/2 (E3.7)."""
        dt, n = self.dt, self.n
        F = np.eye(n)
        F[0, 2] = F[1, 3] = dt
        if n == 6:
            F[2, 4] = F[3, 5] = dt
            F[0, 4] = F[1, 5] = dt * dt / 2.0  # eq. (17) of paper 3, corrected (E3.7)
        return F

    @property
    def H(self) -> FloatArray:
        """Observation matrix H = [I₂ 0 …], eq. (18)."""
        H = np.zeros((2, self.n))
        H[0, 0] = H[1, 1] = 1.0
        return H

    @property
    def Q(self) -> FloatArray:
        """Process noise covariance (SPEC §3.3)."""
        d = np.zeros(self.n)
        d[-2:] = self.q
        return np.diag(d)

    @property
    def Q_rel(self) -> FloatArray:
        """Process noise covariance of the relation filters."""
        q = 0.01 * self.q if self.q_rel is None else self.q_rel  # Q_r = 0.01·Q_c (E3.12)
        d = np.zeros(self.n)
        d[-2:] = q
        return np.diag(d)

    @property
    def R_cell(self) -> FloatArray:
        """R_c (2, 2)."""
        return self.r_cell * np.eye(2)

    @property
    def R_rel(self) -> FloatArray:
        """R_r (2, 2), default 2·R_c."""
        r = 2.0 * self.r_cell if self.r_rel is None else self.r_rel
        return r * np.eye(2)

    def P0(self, r: float) -> FloatArray:
        """Initial covariance diag(r·I₂, p0_vel·I₂[, p0_acc·I₂])."""
        d = [r, r, self.p0_vel, self.p0_vel] + ([self.p0_acc] * 2 if self.n == 6 else [])
        return np.diag(np.asarray(d, dtype=float))


# --------------------------------------------------------------------------- batched KF


def kf_predict(
    x: FloatArray, P: FloatArray, F: FloatArray, Q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Batched time update over any leading dimensions: x⁻ = Φx, P⁻ = ΦPΦᵀ + Q (eqs. 9, 11)."""
    x_new = x @ F.T  # eq. (9)/(11) of paper 3
    P_new = F @ P @ F.T + Q
    return x_new, 0.5 * (P_new + np.swapaxes(P_new, -1, -2))


def kf_gain(P: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    """Kalman gain K = P⁻Hᵀ(HP⁻Hᵀ + R)⁻¹ over leading dimensions (…, n, m)."""
    PHt = P @ H.T
    S = H @ PHt + R
    # K = PHᵀ S⁻¹  ⇔  Kᵀ = S⁻¹ (PHᵀ)ᵀ, S symmetric
    return np.swapaxes(np.linalg.solve(S, np.swapaxes(PHt, -1, -2)), -1, -2)


def kf_riccati(P: FloatArray, K: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    """Posterior covariance in Joseph form, (I − KH)P⁻(I − KH)ᵀ + KRKᵀ (E3.9)."""
    A = np.eye(P.shape[-1]) - K @ H
    out = A @ P @ np.swapaxes(A, -1, -2) + K @ R @ np.swapaxes(K, -1, -2)
    return 0.5 * (out + np.swapaxes(out, -1, -2))


def kf_update(
    x: FloatArray,
    P: FloatArray,
    z: FloatArray,
    H: FloatArray,
    R: FloatArray,
    mask: BoolArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Batched standard measurement update; rows with ``mask`` False or NaN in ``z`` coast."""
    ok = np.all(np.isfinite(z), axis=-1)
    if mask is not None:
        ok &= np.asarray(mask, dtype=bool)
    K = kf_gain(P, H, R)
    nu = np.where(ok[..., None], z, 0.0) - np.where(ok[..., None], x @ H.T, 0.0)
    x_new = x + (K @ nu[..., None])[..., 0]
    P_new = np.where(ok[..., None, None], kf_riccati(P, K, H, R), P)
    return x_new, P_new


# --------------------------------------------------------------------------- state


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
    xc, Pc = kf_predict(state.xc, state.Pc, F, params.Q)  # eqs. (9), (10)
    xr, Pr = kf_predict(state.xr, state.Pr, F, params.Q_rel)  # eqs. (11), (12)
    return SKFState(xc, Pc, xr, Pr)


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
    Kc = kf_gain(state.Pc, H, params.R_cell)  # (N, K, n, 2)
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
    Pc = np.where(cell_info[..., None, None], kf_riccati(state.Pc, Kc, H, params.R_cell), state.Pc)

    # relations: eq. (15) measurement, eq. (14) update
    # (15) blends the cells' priors (SPEC order); option: their posteriors, after (13)
    mr = mr_prior if params.order == "relations-first" else relation_measurement(
        graph, z, alpha, xc[..., :2])
    # SPEC §3.3 "No match": the terms of an unmatched part are dropped, so a relation with an
    # unmatched end has no measurement and coasts (with α^j = 1, (15) would measure the
    # relation by its own prediction, a loop that lets the offset drift without bound).
    matched = np.all(np.isfinite(z), axis=-1)
    rel_ok = matched[:, graph.edges[:, 0]] & matched[:, graph.edges[:, 1]]
    R_rel = np.broadcast_to(params.R_rel, (*state.xr.shape[:2], 2, 2))
    if params.relation_noise == "occlusion":
        # option (not in paper 3): the blend of (15) carries the information of the measured
        # fractions only, so R_r is divided by (1 − α^i)(1 − α^j)
        info = w[:, graph.edges[:, 0]] * w[:, graph.edges[:, 1]]
        rel_ok &= info > 1e-6
        R_rel = R_rel / np.maximum(info, 1e-6)[..., None, None]
    Kr = kf_gain(state.Pr, H, R_rel)
    gain_r = np.where(rel_ok[..., None, None], Kr, 0.0)
    xr = state.xr + (gain_r @ (mr - state.xr[..., :2])[..., None])[..., 0]  # eq. (14) of paper 3
    Pr = np.where(rel_ok[..., None, None], kf_riccati(state.Pr, Kr, H, R_rel), state.Pr)
    # our addition (not in paper 3): a coasting relation's derivatives decay geometrically, so
    # a part hidden for many frames keeps a bounded offset from its neighbours.
    xr[..., 2:] *= np.where(rel_ok, 1.0, params.relation_damping)[..., None]

    terms = SKFTerms(term2, term3, mr, head, tail)
    return SKFState(xc, Pc, xr, Pr), terms


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


def search_region(centres: FloatArray, wh: FloatArray, scale: float = 1.5) -> FloatArray:
    """Search box of each object (SPEC §3.3, E3.10).

    The minimum enclosing rectangle (MER) of the parts' last bounding boxes moved to their
    predicted centres, with its sides scaled by ``scale`` about its centre.

    Parameters
    ----------
    centres : (N, K, 2)
        Predicted part centres m_c^{j−}.
    wh : (N, K, 2)
        Last known box sizes of the parts (NaN rows are ignored).
    scale : float
        Side factor (1.5 in paper 3).

    Returns
    -------
    (N, 4)
        Boxes ``x0, y0, x1, y1``; NaN for an object with no usable part.
    """
    centres = np.asarray(centres, dtype=float)
    wh = np.asarray(wh, dtype=float)
    if centres.shape != wh.shape or centres.ndim != 3 or centres.shape[-1] != 2:
        raise ValueError(f"centres and wh must both be (N, K, 2); got {centres.shape}, {wh.shape}")
    if not scale > 0:
        raise ValueError(f"scale must be > 0, got {scale}")
    ok = np.all(np.isfinite(centres) & np.isfinite(wh), axis=-1, keepdims=True)
    lo = np.where(ok, centres - wh / 2.0, np.inf).min(axis=1)
    hi = np.where(ok, centres + wh / 2.0, -np.inf).max(axis=1)
    any_ok = ok[..., 0].any(axis=1)[:, None]
    lo, hi = np.where(any_ok, lo, np.nan), np.where(any_ok, hi, np.nan)
    mid, half = (lo + hi) / 2.0, (hi - lo) / 2.0 * scale
    box = np.concatenate([mid - half, mid + half], axis=1)
    return np.where(any_ok, box, np.nan)


# --------------------------------------------------------------------------- thin classes


@dataclass
class StructuredKalmanFilter:
    """A structured Kalman filter for objects sharing one part graph (thin wrapper).

    Examples
    --------
    >>> g = PartGraph.chain(3)                       # head–torso–legs
    >>> skf = StructuredKalmanFilter(g)
    >>> s = skf.init(np.array([[[20., 106.], [20., 127.], [20., 159.]]]))
    >>> s = skf.predict(s)
    >>> s, terms = skf.update(s, np.array([[[22., 106.], [22., 127.], [np.nan, np.nan]]]),
    ...                       np.array([[0.0, 0.0, 1.0]]))
    """

    graph: PartGraph
    params: SKFParams = field(default_factory=SKFParams)

    def init(self, z: FloatArray) -> SKFState:
        """See :func:`init`."""
        return init(self.params, self.graph, z)

    def predict(self, state: SKFState) -> SKFState:
        """See :func:`predict`."""
        return predict(self.params, state)

    def update(
        self, state: SKFState, z: FloatArray, alpha: FloatArray
    ) -> tuple[SKFState, SKFTerms]:
        """See :func:`update`."""
        return update(self.params, self.graph, state, z, alpha)

    def add_part(
        self, state: SKFState, xy: FloatArray, neighbours: list[int]
    ) -> tuple[StructuredKalmanFilter, SKFState]:
        """See :func:`add_part`; returns a new filter with the grown graph."""
        graph, new = add_part(self.params, self.graph, state, xy, neighbours)
        return dataclasses.replace(self, graph=graph), new


@dataclass
class StructuredPredictorState:
    """Per-track state of :class:`StructuredPredictor` (leading dimension = tracks).

    ``xc, Pc, xr, Pr`` as in :class:`SKFState`; ``wh`` (N, K, 2) the parts' last box sizes
    (for :meth:`StructuredPredictor.search_region`), NaN when unknown.
    """

    xc: FloatArray
    Pc: FloatArray
    xr: FloatArray
    Pr: FloatArray
    wh: FloatArray

    @property
    def skf(self) -> SKFState:
        """The underlying :class:`SKFState` (views)."""
        return SKFState(self.xc, self.Pc, self.xr, self.Pr)


@dataclass(frozen=True)
class StructuredPredictor:
    """The SKF behind the tracker's :class:`~mvtrack.filters.base.Predictor` protocol.

    Each track is an object with ``K`` parts on a fixed graph (default a vertical chain of
    three, head–torso–legs). The tracker sees whole-object positions: the object position is the
    **mean of its part positions**, and its covariance that of the mean of the cells
    (Σ_j P_j / K², cross-covariances ignored).

    Two ways to feed it:

    - :meth:`update` (the protocol): a whole-object measurement ``z`` (N, 2) is read as the
      translation of the rigid part layout — part j is measured at z + (m_c^{j−} − mean m_c^{−}),
      all with α = 0 — and rows with ``mask`` False coast (α = 1 for every part). This keeps the
      tracker working with plain blob detections; it is then an ordinary Kalman filter per part.
    - :meth:`update_parts`: per-part centroids ``(N, K, 2)`` and occlusion degrees ``(N, K)``
      from :mod:`mvtrack.detection.parts`, which is where the structure pays off: a hidden part
      follows its neighbours through the relation filters (eq. (13) of paper 3).

    :meth:`init` places the parts at ``xy + offsets`` (``offsets`` (K, 2), default a vertical
    head/torso/legs layout of a ~70 px tall person) unless :meth:`init_parts` is used.

    ``r``, ``q`` and ``vel_var`` (the keywords the tracker passes to every predictor) override
    ``params.r_cell``, ``params.q`` and ``params.p0_vel``.
    """

    name: str = "structured"
    params: SKFParams = field(default_factory=SKFParams)
    graph: PartGraph = field(default_factory=lambda: PartGraph.chain(3))
    offsets: FloatArray = field(
        default_factory=lambda: np.array([[0.0, -21.0], [0.0, 0.0], [0.0, 32.0]])
    )
    r: float | None = None
    q: float | None = None
    vel_var: float | None = None

    def __post_init__(self) -> None:
        off = np.asarray(self.offsets, dtype=float)
        if off.shape != (self.graph.n_parts, 2):
            raise ValueError(f"offsets must have shape ({self.graph.n_parts}, 2), got {off.shape}")
        object.__setattr__(self, "offsets", off - off.mean(axis=0))
        # the tracker's common keywords: r (px²), q, vel_var (initial velocity variance)
        changes = {
            name: value
            for name, value in (("r_cell", self.r), ("q", self.q), ("p0_vel", self.vel_var))
            if value is not None
        }
        if changes:
            object.__setattr__(self, "params", dataclasses.replace(self.params, **changes))

    def init_parts(self, z: FloatArray, wh: FloatArray | None = None) -> StructuredPredictorState:
        """State for new tracks from part measurements ``z`` (K, parts, 2)."""
        s = init(self.params, self.graph, z)
        size = np.full((*s.xc.shape[:2], 2), np.nan) if wh is None else np.asarray(wh, float)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, size)

    def init(self, xy: FloatArray) -> StructuredPredictorState:
        """State of new tracks first measured at ``xy`` (K, 2), parts at ``xy + offsets``."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        return self.init_parts(xy[:, None, :] + self.offsets[None])

    def predict(self, state: StructuredPredictorState) -> StructuredPredictorState:
        """Eqs. (9)–(12) for every track."""
        s = predict(self.params, state.skf)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, state.wh)

    def update_parts(
        self,
        state: StructuredPredictorState,
        z: FloatArray,
        alpha: FloatArray,
        wh: FloatArray | None = None,
    ) -> StructuredPredictorState:
        """Eqs. (13)–(15) with part centroids ``z`` (N, K, 2) and occlusion degrees (N, K)."""
        s, _ = update(self.params, self.graph, state.skf, z, alpha)
        size = state.wh
        if wh is not None:
            wh = np.asarray(wh, dtype=float)
            size = np.where(np.all(np.isfinite(wh), axis=-1, keepdims=True), wh, state.wh)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, size)

    def update(
        self, state: StructuredPredictorState, z: FloatArray, mask: BoolArray
    ) -> StructuredPredictorState:
        """Whole-object update: ``z`` (N, 2) moves the rigid part layout; masked rows coast."""
        z = np.asarray(z, dtype=float)
        ok = np.asarray(mask, dtype=bool) & np.all(np.isfinite(z), axis=-1)
        pos = state.xc[..., :2]
        zp = z[:, None, :] + (pos - pos.mean(axis=1, keepdims=True))
        zp = np.where(ok[:, None, None], zp, np.nan)
        alpha = np.where(ok[:, None], 0.0, 1.0) * np.ones(pos.shape[:2])
        return self.update_parts(state, zp, alpha)

    def position(self, state: StructuredPredictorState) -> FloatArray:
        """Object position = mean of the part positions (N, 2)."""
        return state.xc[..., :2].mean(axis=1)

    def velocity(self, state: StructuredPredictorState) -> FloatArray:
        """Mean of the part velocities (N, 2)."""
        return state.xc[..., 2:4].mean(axis=1)

    def position_cov(self, state: StructuredPredictorState) -> FloatArray:
        """Covariance of the mean part position, Σ_j P_j[:2, :2] / K² (N, 2, 2)."""
        K = state.xc.shape[1]
        return state.Pc[..., :2, :2].sum(axis=1) / float(K * K)

    def innovation_cov(self, state: StructuredPredictorState) -> FloatArray:
        """S = P̄ + R_c / K for the mean of K part measurements (N, 2, 2)."""
        K = state.xc.shape[1]
        return self.position_cov(state) + self.params.R_cell / K

    def part_positions(self, state: StructuredPredictorState) -> FloatArray:
        """Part positions (N, K, 2)."""
        return state.xc[..., :2]

    def search_region(self, state: StructuredPredictorState, scale: float = 1.5) -> FloatArray:
        """Search boxes (N, 4) from the predicted parts and their last sizes (E3.10)."""
        return search_region(state.xc[..., :2], state.wh, scale)
