"""Parameters of the structured Kalman filter and the model matrices they define."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from mvtrack.filters.base import FloatArray

__all__ = ["SKFParams"]


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
        Factor ``d`` in [0, 1] applied each frame to the velocity and acceleration of a
        relation with an unmatched end (which coasts, having no measurement). Not in paper 3:
        with 1.0 a CA relation coasting for many frames drifts quadratically; 0.8 bounds the
        drift.
    damping_by : {"alpha", "unmatched"}
        ``"alpha"``: a relation whose ends are both matched is damped by ``d ** α``, ``α`` the
        larger of its ends' occlusion measures (16). Eq. (15) measures such a relation by the
        occluded end's own prediction in proportion to ``α``, the loop the damping exists to
        break; an unmatched end is the limit ``α = 1`` (SPEC §3.3 "No match"), so the two
        cases meet. ``"unmatched"``: only relations with an unmatched end are damped (the
        first reading).
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
    damping_by: Literal["alpha", "unmatched"] = "alpha"
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
        if self.damping_by not in ("alpha", "unmatched"):
            raise ValueError(
                f"damping_by must be 'alpha' or 'unmatched', got {self.damping_by!r}"
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
