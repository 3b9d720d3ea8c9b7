"""``kalman-cv``: the per-axis constant-velocity Kalman filter, in closed form.

The per-axis model :func:`mvtrack.filters.models.constant_velocity` (``H = [1, 0]``) written
out in scalars: both image axes use the same model, the same initial covariance and the same
update mask, so their 2×2 covariances are identical (SPEC E2.3) and one ``(a, b, c)`` triple
per track serves both. A frame then costs a couple of dozen array operations on ``(N,)``
columns instead of batched matrix products, which is what keeps the tracker's small-``N``
cost low. ``make_predictor("kalman-cv")`` and the tracker use this one implementation; the
general per-axis filter (:class:`mvtrack.filters.predictors.PerAxisKalmanPredictor` on the
same model, kernels :func:`mvtrack.filters.fast.kf_axis_predict` and
:func:`~mvtrack.filters.fast.kf_axis_update`) is its oracle: ``tests/filters/test_cv.py`` pins
the two equal to 1e-9, also with a measurement variance per track (the tracker's
box-size scaling, ``TrackerConfig.size_ref``).

With ``P = [[a, b], [b, c]]`` per axis, frame interval Δt (1 frame in the tracker),
``G = [Δt²/2, Δt]ᵀ`` and ``Q = G q Gᵀ``:

.. math::
    \\bar p = p + v Δt,\\quad \\bar a = a + 2 Δt b + Δt^2 c + q Δt^4/4,\\quad
    \\bar b = b + Δt c + q Δt^3/2,\\quad \\bar c = c + q Δt^2
    \\qquad \\text{(eqs. (6)–(7) of paper 1)}

    S = \\bar a + r,\\; K = [\\bar a, \\bar b]^T / S \\;(3),\\quad
    \\hat x = \\bar x + K (z - \\bar p) \\;(4),\\quad
    a = \\bar a r / S,\\; b = \\bar b r / S,\\; c = \\bar c - \\bar b^2 / S \\;(5)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray, check_shapes, check_xy
from mvtrack.filters.models import check_positive

#: the columns of ``(a, b, c)`` that multiply the innovation of ``(px, py, vx, vy)`` in the gain
_GAIN_COLS = np.array([0, 0, 1, 1])


@dataclass(frozen=True)
class CVState:
    """State of ``N`` tracks.

    Attributes
    ----------
    x : (N, 4) float64
        ``[px, py, vx, vy]`` in pixels and pixels per frame.
    P : (N, 3) float64
        ``[a, b, c]``: the per-axis covariance ``[[a, b], [b, c]]`` shared by x and y.
    """

    x: FloatArray
    P: FloatArray


class KalmanCVPredictor:
    """``kalman-cv`` in closed form (implements :class:`mvtrack.filters.base.Predictor`).

    Parameters
    ----------
    q : float
        White-acceleration variance per frame (px²/frame⁴), ``Q = G q Gᵀ``.
    r : float
        Measurement-noise variance (px²).
    vel_var : float
        Initial velocity variance (px²/frame²); a new track starts at its first measurement
        with zero velocity and ``P₀ = diag(r, vel_var)`` per axis.
    dt : float
        Frame interval (1 frame).
    """

    name = "kalman-cv"

    def __init__(
        self, q: float = 0.1, r: float = 1.0, vel_var: float = 25.0, dt: float = 1.0
    ) -> None:
        self.q = check_positive("q", q)
        self.r = check_positive("r", r)
        self.vel_var = check_positive("vel_var", vel_var)
        dt = check_positive("dt", dt)
        self._Ft = np.array(  # x ↦ F x for x = [px, py, vx, vy], as a right multiplication
            [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [dt, 0.0, 1.0, 0.0],
             [0.0, dt, 0.0, 1.0]]
        )
        # (a, b, c) ↦ F P Fᵀ: a + 2Δt b + Δt² c, b + Δt c, c
        self._FPF = np.array([[1.0, 0.0, 0.0], [2.0 * dt, 1.0, 0.0], [dt * dt, dt, 1.0]])
        # G q Gᵀ as (a, b, c), G = [Δt²/2, Δt]ᵀ
        self._qvec = self.q * np.array([0.25 * dt**4, 0.5 * dt**3, dt * dt])
        self._P0 = np.array([self.r, 0.0, self.vel_var])  # diag(r, vel_var) as (a, b, c)

    def init(self, xy: FloatArray, r: FloatArray | None = None) -> CVState:
        """``K`` new tracks at ``xy`` (K, 2) with zero velocity.

        ``r`` (K,), optional: per-track measurement variances instead of ``self.r``
        (``P₀ = diag(r_i, vel_var)``).
        """
        xy = check_xy("xy", xy)
        k = xy.shape[0]
        x = np.zeros((k, 4))
        x[:, :2] = xy
        P = np.empty((k, 3))
        P[:] = self._P0
        if r is not None:
            P[:, 0] = r
        return CVState(x, P)

    def predict(self, state: CVState) -> CVState:
        """Time update of every track, eqs. (6)–(7) of paper 1 in closed form."""
        x = state.x @ self._Ft  # eq. (6): p + v Δt, v
        P = state.P @ self._FPF + self._qvec  # eq. (7): F P Fᵀ + G q Gᵀ on (a, b, c)
        return CVState(x, P)

    def update(
        self, state: CVState, z: FloatArray, mask: BoolArray, r: FloatArray | None = None
    ) -> CVState:
        """Measurement update, eqs. (3)–(5); rows with ``mask`` False or NaN keep the prediction.

        ``r`` (N,), optional: per-track measurement variances instead of ``self.r``.
        """
        x, P = state.x, state.P
        z, mask = check_shapes(z, mask, x.shape[0])
        nu = z - x[:, :2]  # innovation per axis (NaN where missing)
        both = nu[:, 0] + nu[:, 1]
        ok = mask & (both == both)  # and neither coordinate NaN
        w = ok / (P[:, 0] + (self.r if r is None else r))  # 1/S, eq. (3); 0 where no measurement
        gain = P.take(_GAIN_COLS, 1) * w[:, None]  # K = [a, b]ᵀ / S, eq. (3), as (a, a, b, b)/S
        np.copyto(nu, 0.0, where=~ok[:, None])
        xn = x + gain * np.concatenate((nu, nu), axis=1)  # eq. (4) for (px, py, vx, vy)
        Pn = P * (1.0 - gain[:, 0])[:, None]  # eq. (5): a r/S, b r/S, c − b²/S
        Pn[:, 2] = P[:, 2] - P[:, 1] * gain[:, 2]
        return CVState(xn, Pn)

    def covariance(self, state: CVState) -> FloatArray:
        """Full per-axis covariances (N, 2, 2, 2): ``[[a, b], [b, c]]`` for x and for y."""
        a, b, c = state.P[:, 0], state.P[:, 1], state.P[:, 2]
        full = np.stack([np.stack([a, b], -1), np.stack([b, c], -1)], -2)  # (N, 2, 2)
        return np.repeat(full[:, None], 2, axis=1)

    def position(self, state: CVState) -> FloatArray:
        """Position (N, 2)."""
        return state.x[:, :2]

    def velocity(self, state: CVState) -> FloatArray:
        """Velocity (N, 2), px/frame."""
        return state.x[:, 2:]

    def position_var(self, state: CVState) -> FloatArray:
        """Position variance per axis (N,) — the same for x and y."""
        return state.P[:, 0]

    def position_cov(self, state: CVState) -> FloatArray:
        """Position covariance (N, 2, 2), ``a I``."""
        return state.P[:, 0, None, None] * np.eye(2)

    def innovation_cov(self, state: CVState) -> FloatArray:
        """Innovation covariance (N, 2, 2), ``(a + r) I``."""
        return (state.P[:, 0, None, None] + self.r) * np.eye(2)
