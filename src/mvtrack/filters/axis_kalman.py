"""Per-axis linear Kalman predictors (``kalman-ca``): x and y as two filters of one 1-D model.

Both axes of ``N`` tracks are ``2N`` filters advanced together by the closed-form kernels of
:mod:`mvtrack.filters.fast` (equal to :func:`mvtrack.filters.kalman.predict` /
:func:`~mvtrack.filters.kalman.update`, tested). Initial covariance (SPEC E1.11): a new track
starts at its first measurement with zero velocity and acceleration,
``P₀ = diag(r, vel_var[, acc_var])`` per axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.filters import fast
from mvtrack.filters.base import BoolArray, FloatArray, check_xy, check_z_mask
from mvtrack.filters.layout import axes_flat, diag2, from_components, to_components
from mvtrack.filters.models import (
    LinearModel,
    check_positive,
    constant_acceleration,
)

__all__ = ["AxisKalmanState", "KalmanCAPredictor", "PerAxisKalmanPredictor"]


@dataclass(frozen=True)
class AxisKalmanState:
    """Per-axis Kalman state of ``N`` tracks (x and y filters of one 1-D model).

    Attributes
    ----------
    x : ndarray (N, 2, n)
        States ``[p, v(, a)]`` of the x and y filters.
    P : ndarray (N, 2, n(n+1)/2)
        Covariances, packed upper triangle (``mvtrack.filters.fast.unpack`` gives the full
        matrices; :meth:`PerAxisKalmanPredictor.covariance` too).

    The arrays are stored component-first in memory (their transposes are C-contiguous) so
    the per-frame kernels run on contiguous vectors; ``take``/``concat`` work as usual.
    """

    x: FloatArray
    P: FloatArray


class PerAxisKalmanPredictor:
    """Per-axis linear KF (x and y as two independent filters of one 1-D model).

    All ``2N`` filters are advanced together by the closed-form kernels of
    :mod:`mvtrack.filters.fast` (equal to :func:`mvtrack.filters.kalman.predict` /
    :func:`~mvtrack.filters.kalman.update`, tested).

    Parameters
    ----------
    model : LinearModel
        1-D model with H selecting the position, ``H = [1, 0, …]`` (m = 1).
    vel_var : float
        Initial velocity variance per axis (px²/frame²).
    acc_var : float
        Initial acceleration variance per axis, used when the model has 3 states.
    name : str
        Registry name.
    """

    def __init__(
        self, model: LinearModel, vel_var: float = 25.0, acc_var: float = 1.0, name: str = ""
    ) -> None:
        if model.m != 1 or not np.array_equal(model.H[0], np.eye(model.n)[0]):
            raise ValueError("model.H must select the position: H = [1, 0, ...]")
        self.model = model
        self.name = name
        self.vel_var = check_positive("vel_var", vel_var)
        self.acc_var = check_positive("acc_var", acc_var)
        self.r = float(model.R[0, 0])
        p0 = [self.r, self.vel_var, self.acc_var][: model.n] + [self.acc_var] * (model.n - 3)
        self._P0 = np.diag(p0)

    def init(self, xy: FloatArray) -> AxisKalmanState:
        """State of ``K`` new tracks at ``xy`` (K, 2): zero velocity, ``P₀ = diag(r, vel_var…)``."""
        xy = check_xy("xy", xy)
        if not np.all(np.isfinite(xy)):
            raise ValueError("xy holds NaN or infinite values")
        K, n = xy.shape[0], self.model.n
        x = np.zeros((n, 2, K))
        x[0] = xy.T
        P = np.empty((n * (n + 1) // 2, 2, K))
        P[:] = fast.pack(self._P0)[:, None, None]
        return AxisKalmanState(x=np.transpose(x, (2, 1, 0)), P=np.transpose(P, (2, 1, 0)))

    def predict(self, state: AxisKalmanState) -> AxisKalmanState:
        """Time update, eqs. (6)–(7) of paper 1, of every track and axis."""
        N = state.x.shape[0]
        x, P = fast.kf_axis_predict(to_components(state.x), to_components(state.P), self.model.F,
                                    self.model.Q)
        return AxisKalmanState(x=from_components(x, N), P=from_components(P, N))

    def update(self, state: AxisKalmanState, z: FloatArray, mask: BoolArray) -> AxisKalmanState:
        """Measurement update, eqs. (3)–(5); rows with mask False or NaN keep the prediction."""
        N = state.x.shape[0]
        z, ok = check_z_mask(z, mask, N)
        x, P = fast.kf_axis_update(
            to_components(state.x), to_components(state.P), axes_flat(z), self.r,
            np.concatenate([ok, ok]),
        )
        return AxisKalmanState(x=from_components(x, N), P=from_components(P, N))

    def covariance(self, state: AxisKalmanState) -> FloatArray:
        """Full per-axis covariances (N, 2, n, n)."""
        return fast.unpack(state.P, self.model.n)

    def position(self, state: AxisKalmanState) -> FloatArray:
        """Position estimate (N, 2): ``H x`` per axis."""
        return state.x[:, :, 0].copy()

    def velocity(self, state: AxisKalmanState) -> FloatArray:
        """Velocity estimate (N, 2), px/frame."""
        return state.x[:, :, 1].copy()

    def position_cov(self, state: AxisKalmanState) -> FloatArray:
        """Diagonal position covariance (N, 2, 2): ``P[0, 0]`` of each axis."""
        return diag2(state.P[:, :, 0])

    def innovation_cov(self, state: AxisKalmanState) -> FloatArray:
        """Diagonal innovation covariance (N, 2, 2): ``S = P[0, 0] + r`` per axis."""
        return diag2(state.P[:, :, 0] + self.r)


class KalmanCAPredictor(PerAxisKalmanPredictor):
    """``kalman-ca``: per-axis constant-acceleration KF of paper 1, eqs. (3)–(9).

    Parameters
    ----------
    q : float
        Process-noise variance of the acceleration (px²/frame⁴), ``Q = diag(0, 0, q)``.
    r : float
        Measurement-noise variance (px²).
    vel_var, acc_var : float
        Initial velocity and acceleration variances.
    dt : float
        Frame interval (1 frame).
    """

    def __init__(
        self,
        q: float = 0.1,
        r: float = 1.0,
        vel_var: float = 25.0,
        acc_var: float = 1.0,
        dt: float = 1.0,
    ) -> None:
        super().__init__(constant_acceleration(dt, q, r), vel_var, acc_var, name="kalman-ca")
