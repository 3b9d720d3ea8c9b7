"""``kalman-coupled``: one 2-D Kalman filter per track, x and y in one state.

The full 2×2 position covariance is what the x-y coupled confidence region of paper 2 needs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from mvtrack.filters import fast
from mvtrack.filters.base import BoolArray, FloatArray, check_xy, check_z_mask
from mvtrack.filters.models import (
    check_positive,
    coupled,
)

__all__ = ["CoupledKalmanPredictor", "KalmanState"]


@dataclass(frozen=True)
class KalmanState:
    """Coupled Kalman state of ``N`` tracks.

    Attributes
    ----------
    x : ndarray (N, n)
        States ``[x, y, vx, vy(, ax, ay)]``.
    P : ndarray (N, n(n+1)/2)
        Covariances, packed upper triangle (:meth:`CoupledKalmanPredictor.covariance` gives
        the full matrices). Stored component-first in memory, like :class:`AxisKalmanState`.
    """

    x: FloatArray
    P: FloatArray


class CoupledKalmanPredictor:
    """``kalman-coupled``: one 2-D KF per track with state ``[x, y, vx, vy(, ax, ay)]``.

    The full 2×2 position covariance is what the x-y coupled confidence region of paper 2
    needs. Parameters as for the per-axis classes; ``kind`` is ``"cv"`` (default) or ``"ca"``.
    """

    name = "kalman-coupled"

    def __init__(
        self,
        q: float = 0.1,
        r: float = 1.0,
        vel_var: float = 25.0,
        acc_var: float = 1.0,
        dt: float = 1.0,
        kind: Literal["cv", "ca"] = "cv",
    ) -> None:
        self.model = coupled(kind, dt, q, r)
        self.vel_var = check_positive("vel_var", vel_var)
        self.acc_var = check_positive("acc_var", acc_var)
        self.r = float(r)
        diag = [self.r, self.r, self.vel_var, self.vel_var, self.acc_var, self.acc_var]
        self._P0 = np.diag(diag[: self.model.n])
        self._pos_idx = fast.packed_index(self.model.n)[:2, :2]

    def init(self, xy: FloatArray) -> KalmanState:
        """State of ``K`` new tracks at ``xy`` (K, 2), zero velocity."""
        xy = check_xy("xy", xy)
        if not np.all(np.isfinite(xy)):
            raise ValueError("xy holds NaN or infinite values")
        K, n = xy.shape[0], self.model.n
        x = np.zeros((n, K))
        x[:2] = xy.T
        P = np.empty((n * (n + 1) // 2, K))
        P[:] = fast.pack(self._P0)[:, None]
        return KalmanState(x=x.T, P=P.T)

    def predict(self, state: KalmanState) -> KalmanState:
        """Time update, eqs. (6)–(7) of paper 1."""
        x, P = fast.kf_axis_predict(np.ascontiguousarray(state.x.T),
                                    np.ascontiguousarray(state.P.T), self.model.F, self.model.Q)
        return KalmanState(x=x.T, P=P.T)

    def update(self, state: KalmanState, z: FloatArray, mask: BoolArray) -> KalmanState:
        """Measurement update, eqs. (3)–(5); rows with mask False or NaN keep the prediction."""
        z, ok = check_z_mask(z, mask, state.x.shape[0])
        x, P = fast.kf_select_update(np.ascontiguousarray(state.x.T),
                                     np.ascontiguousarray(state.P.T),
                                     np.ascontiguousarray(z.T), self.model.R, ok)
        return KalmanState(x=x.T, P=P.T)

    def covariance(self, state: KalmanState) -> FloatArray:
        """Full covariances (N, n, n)."""
        return fast.unpack(state.P, self.model.n)

    def position(self, state: KalmanState) -> FloatArray:
        """Position estimate (N, 2)."""
        return state.x[:, :2].copy()

    def velocity(self, state: KalmanState) -> FloatArray:
        """Velocity estimate (N, 2), px/frame."""
        return state.x[:, 2:4].copy()

    def position_cov(self, state: KalmanState) -> FloatArray:
        """Full 2×2 position covariance (N, 2, 2)."""
        return state.P[:, self._pos_idx]

    def innovation_cov(self, state: KalmanState) -> FloatArray:
        """``S = P_pos + R`` (N, 2, 2)."""
        return state.P[:, self._pos_idx] + self.model.R
