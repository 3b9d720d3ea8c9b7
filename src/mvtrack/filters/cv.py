"""``kalman-cv``: the per-axis constant-velocity Kalman filter, in closed form.

The per-axis model :func:`mvtrack.filters.models.constant_velocity` (``H = [1, 0]``) written
out in scalars. Each image axis of each track has its own 2×2 covariance ``[[a, b], [b, c]]``
(position, velocity) and its own noise: the tracker gives every track a measurement variance
``r`` and a white-acceleration variance ``q`` per axis, proportional to its box's width (x)
and height (y) (:mod:`mvtrack.tracking.noise`), so one filter serves a far pedestrian of
40 px and a near bus of 400 px. The general per-axis filter
(:class:`mvtrack.filters.predictors.PerAxisKalmanPredictor` on the same model) is its oracle:
``tests/filters/test_cv.py`` pins the two equal to 1e-9.

With frame interval Δt, ``G = [Δt²/2, Δt]ᵀ`` and ``Q = G q Gᵀ``, per axis:

.. math::
    \\bar p = p + v Δt,\\quad \\bar a = a + 2 Δt b + Δt^2 c + q Δt^4/4,\\quad
    \\bar b = b + Δt c + q Δt^3/2,\\quad \\bar c = c + q Δt^2
    \\qquad \\text{(eqs. (6)–(7) of paper 1)}

    S = \\bar a + r,\\; K = [\\bar a, \\bar b]^T / S \\;(3),\\quad
    \\hat x = \\bar x + K (z - \\bar p) \\;(4),\\quad
    a = \\bar a r / S,\\; b = \\bar b r / S,\\; c = \\bar c - \\bar b^2 / S \\;(5)

:func:`cv_predict` and :func:`cv_update` are compiled kernels (:func:`mvtrack.jit.kernel`);
:class:`KalmanCVPredictor` is the :class:`~mvtrack.filters.base.Predictor` around them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray, check_shapes, check_xy
from mvtrack.filters.models import check_positive
from mvtrack.jit import kernel


@dataclass(frozen=True)
class CVState:
    """State of ``N`` tracks.

    Attributes
    ----------
    x : (N, 4) float64
        ``[px, py, vx, vy]`` in pixels and pixels per frame.
    P : (N, 2, 3) float64
        Per axis (x, then y) the covariance ``[[a, b], [b, c]]`` as ``(a, b, c)``.
    """

    x: FloatArray
    P: FloatArray


@kernel
def cv_predict(x: FloatArray, P: FloatArray, q: FloatArray, dt: float
               ) -> tuple[FloatArray, FloatArray]:
    """Time update of ``N`` tracks, eqs. (6)–(7) of paper 1 per axis.

    ``q`` (N, 2): white-acceleration variance of each track and axis (px²/frame⁴ for
    ``dt = 1``). Returns the new ``x`` (N, 4) and ``P`` (N, 2, 3).
    """
    n = x.shape[0]
    xo = np.empty_like(x)
    Po = np.empty_like(P)
    dt2 = dt * dt
    for i in range(n):
        for ax in range(2):
            a, b, c, qi = P[i, ax, 0], P[i, ax, 1], P[i, ax, 2], q[i, ax]
            Po[i, ax, 0] = a + 2.0 * dt * b + dt2 * c + 0.25 * qi * dt2 * dt2  # eq. (7)
            Po[i, ax, 1] = b + dt * c + 0.5 * qi * dt2 * dt  # eq. (7)
            Po[i, ax, 2] = c + qi * dt2  # eq. (7)
            xo[i, ax] = x[i, ax] + dt * x[i, 2 + ax]  # eq. (6): p + v Δt
            xo[i, 2 + ax] = x[i, 2 + ax]
    return xo, Po


@kernel
def cv_update(x: FloatArray, P: FloatArray, z: FloatArray, mask: BoolArray, r: FloatArray
              ) -> tuple[FloatArray, FloatArray]:
    """Measurement update, eqs. (3)–(5) of paper 1 per axis.

    ``z`` (N, 2) measured positions, ``mask`` (N,) the rows that have one (a row with a NaN
    coordinate has none), ``r`` (N, 2) measurement variances. Rows without a measurement keep
    the prediction.
    """
    xo = x.copy()
    Po = P.copy()
    for i in range(x.shape[0]):
        if not mask[i] or z[i, 0] != z[i, 0] or z[i, 1] != z[i, 1]:
            continue
        for ax in range(2):
            a, b, c = P[i, ax, 0], P[i, ax, 1], P[i, ax, 2]
            s = a + r[i, ax]  # S = P̄ + r, eq. (3)
            ka, kb = a / s, b / s  # K = [a, b]ᵀ / S, eq. (3)
            nu = z[i, ax] - x[i, ax]
            xo[i, ax] = x[i, ax] + ka * nu  # eq. (4)
            xo[i, 2 + ax] = x[i, 2 + ax] + kb * nu  # eq. (4)
            Po[i, ax, 0] = a * (1.0 - ka)  # eq. (5): a r / S
            Po[i, ax, 1] = b * (1.0 - ka)  # eq. (5): b r / S
            Po[i, ax, 2] = c - b * kb  # eq. (5): c − b² / S
    return xo, Po


class KalmanCVPredictor:
    """``kalman-cv`` in closed form (implements :class:`mvtrack.filters.base.Predictor`).

    Parameters
    ----------
    q : float
        White-acceleration variance per frame (px²/frame⁴), ``Q = G q Gᵀ``, for the tracks
        given no ``q`` of their own.
    r : float
        Measurement-noise variance (px²), likewise.
    vel_var : float
        Initial velocity variance (px²/frame²); a new track starts at its first measurement
        with zero velocity and ``P₀ = diag(r, vel_var)`` per axis.
    dt : float
        Frame interval (1 frame).

    Every method that uses a noise takes optional per-track, per-axis values (``(N, 2)``
    arrays) that replace these scalars (``noise_per_track``).
    """

    name = "kalman-cv"
    #: predict, update and init take per-track, per-axis noise (:mod:`mvtrack.tracking.noise`)
    noise_per_track = True

    def __init__(
        self, q: float = 0.1, r: float = 1.0, vel_var: float = 25.0, dt: float = 1.0
    ) -> None:
        self.q = check_positive("q", q)
        self.r = check_positive("r", r)
        self.vel_var = check_positive("vel_var", vel_var)
        self.dt = check_positive("dt", dt)

    def _noise(self, value: FloatArray | None, default: float, n: int) -> FloatArray:
        if value is None:
            return np.full((n, 2), default)
        v = np.asarray(value, dtype=np.float64)
        return np.broadcast_to(v.reshape(n, -1), (n, 2)) if v.ndim < 2 else v

    def init(self, xy: FloatArray, r: FloatArray | None = None,
             vel_var: FloatArray | None = None) -> CVState:
        """``K`` new tracks at ``xy`` (K, 2) with zero velocity, ``P₀ = diag(r, vel_var)`` per
        axis (``r``, ``vel_var``: (K, 2) or (K,) per track, default the scalars)."""
        xy = check_xy("xy", xy)
        k = xy.shape[0]
        x = np.zeros((k, 4))
        x[:, :2] = xy
        P = np.zeros((k, 2, 3))
        P[:, :, 0] = self._noise(r, self.r, k)
        P[:, :, 2] = self._noise(vel_var, self.vel_var, k)
        return CVState(x, P)

    def predict(self, state: CVState, q: FloatArray | None = None) -> CVState:
        """Time update of every track, eqs. (6)–(7) of paper 1 (``q``: (N, 2) per track)."""
        n = state.x.shape[0]
        return CVState(*cv_predict(state.x, state.P, self._noise(q, self.q, n), self.dt))

    def update(
        self, state: CVState, z: FloatArray, mask: BoolArray, r: FloatArray | None = None
    ) -> CVState:
        """Measurement update, eqs. (3)–(5); rows with ``mask`` False or NaN keep the prediction
        (``r``: (N, 2) or (N,) per track)."""
        n = state.x.shape[0]
        z, mask = check_shapes(z, mask, n)
        return CVState(*cv_update(state.x, state.P, z, mask,
                                  np.ascontiguousarray(self._noise(r, self.r, n))))

    def covariance(self, state: CVState) -> FloatArray:
        """Full per-axis covariances (N, 2, 2, 2): ``[[a, b], [b, c]]`` for x and for y."""
        a, b, c = state.P[..., 0], state.P[..., 1], state.P[..., 2]
        return np.stack([np.stack([a, b], -1), np.stack([b, c], -1)], -2)

    def position(self, state: CVState) -> FloatArray:
        """Position (N, 2)."""
        return state.x[:, :2]

    def velocity(self, state: CVState) -> FloatArray:
        """Velocity (N, 2), px/frame."""
        return state.x[:, 2:]

    def position_var(self, state: CVState) -> FloatArray:
        """Position variance per axis (N, 2)."""
        return state.P[:, :, 0]

    def position_cov(self, state: CVState) -> FloatArray:
        """Position covariance (N, 2, 2), ``diag(a_x, a_y)``."""
        out = np.zeros((state.x.shape[0], 2, 2))
        out[:, 0, 0], out[:, 1, 1] = state.P[:, 0, 0], state.P[:, 1, 0]
        return out

    def innovation_cov(self, state: CVState, r: FloatArray | None = None) -> FloatArray:
        """Innovation covariance (N, 2, 2), ``diag(a_x + r_x, a_y + r_y)``."""
        out = self.position_cov(state)
        rr = self._noise(r, self.r, state.x.shape[0])
        out[:, 0, 0] += rr[:, 0]
        out[:, 1, 1] += rr[:, 1]
        return out
