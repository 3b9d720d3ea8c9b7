"""``kalman-imm``: two constant-velocity Kalman filters, steady and manoeuvring, mixed (IMM).

An object mostly moves steadily — a walker, a car in its lane — and now and then turns, brakes
or starts: the interacting multiple model (IMM) filter of Blom and Bar-Shalom runs both
hypotheses per track, the per-axis CV filter of :mod:`mvtrack.filters.cv` with a small
white-acceleration variance ``q₀`` (*steady*) and with a large one ``q₁`` (*manoeuvring*),
and weighs them each frame by how well each predicted the measurement. A steady track keeps
the steady model's tight prediction and gate; a turning one moves to the manoeuvring model
within a frame or two, and its gate opens to follow it.

With mode probabilities ``μ`` and the Markov switching matrix ``Π`` (``π_ij`` the probability
of moving from mode ``i`` to ``j`` in one frame), per track:

.. math::
    c_j = \\sum_i π_{ij} μ_i,\\quad μ_{i|j} = π_{ij} μ_i / c_j \\quad\\text{(mixing)}

    x^0_j = \\sum_i μ_{i|j} x_i,\\quad
    P^0_j = \\sum_i μ_{i|j} \\left(P_i + (x_i - x^0_j)(x_i - x^0_j)^T\\right)

then each model's prediction (eqs. (6)–(7) of paper 1) from its mixed state, and after the
measurement each model's update (eqs. (3)–(5)) and

.. math:: μ_j \\propto c_j\\, \\mathcal N(ν_j; 0, S_j)

(a track without measurement keeps ``μ = c``). The combined estimate and its covariance —
what the tracker gates and writes — are the moment-matched mixture
``x̄ = Σ c_j x̄_j``, ``P̄ = Σ c_j (P̄_j + (x̄_j − x̄)(x̄_j − x̄)ᵀ)``. Each axis has its own
``(a, b, c)`` covariance per model, as in :mod:`mvtrack.filters.cv`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray, check_shapes, check_xy
from mvtrack.filters.models import check_positive
from mvtrack.jit import kernel


@dataclass(frozen=True)
class IMMState:
    """State of ``N`` tracks.

    Attributes
    ----------
    x : (N, 2, 4) float64
        Per model (steady, manoeuvring) ``[px, py, vx, vy]`` in pixels and pixels per frame.
    P : (N, 2, 2, 3) float64
        Per model and axis the covariance ``[[a, b], [b, c]]`` as ``(a, b, c)``.
    mu : (N, 2) float64
        Mode probabilities (after :meth:`~KalmanIMMPredictor.predict`: the predicted ones).
    """

    x: FloatArray
    P: FloatArray
    mu: FloatArray


@kernel
def imm_predict(x: FloatArray, P: FloatArray, mu: FloatArray, q: FloatArray,
                pi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Mixing and time update of ``N`` tracks (module docstring).

    ``q`` (N, 2, 2): white-acceleration variance per track, model and axis (px²/frame⁴);
    ``pi`` (2, 2): the switching probabilities per frame. Returns ``x``, ``P`` and the
    predicted mode probabilities ``c``.
    """
    n = x.shape[0]
    xo = np.empty_like(x)
    Po = np.empty_like(P)
    mo = np.empty_like(mu)
    for t in range(n):
        for j in range(2):
            c = pi[0, j] * mu[t, 0] + pi[1, j] * mu[t, 1]
            mo[t, j] = c
            w0 = pi[0, j] * mu[t, 0] / c if c > 0.0 else 1.0  # μ_{0|j} (a mode of weight 0:
            w1 = 1.0 - w0  # its mixed state is the steady model's, never used)
            for ax in range(2):
                p0, v0 = x[t, 0, ax], x[t, 0, 2 + ax]
                p1, v1 = x[t, 1, ax], x[t, 1, 2 + ax]
                pm, vm = w0 * p0 + w1 * p1, w0 * v0 + w1 * v1  # x⁰_j
                d0p, d0v, d1p, d1v = p0 - pm, v0 - vm, p1 - pm, v1 - vm
                a = w0 * (P[t, 0, ax, 0] + d0p * d0p) + w1 * (P[t, 1, ax, 0] + d1p * d1p)
                b = w0 * (P[t, 0, ax, 1] + d0p * d0v) + w1 * (P[t, 1, ax, 1] + d1p * d1v)
                cc = w0 * (P[t, 0, ax, 2] + d0v * d0v) + w1 * (P[t, 1, ax, 2] + d1v * d1v)
                qi = q[t, j, ax]
                Po[t, j, ax, 0] = a + 2.0 * b + cc + 0.25 * qi  # eq. (7), Δt = 1
                Po[t, j, ax, 1] = b + cc + 0.5 * qi
                Po[t, j, ax, 2] = cc + qi
                xo[t, j, ax] = pm + vm  # eq. (6)
                xo[t, j, 2 + ax] = vm
    return xo, Po, mo


@kernel
def imm_update(x: FloatArray, P: FloatArray, mu: FloatArray, z: FloatArray,
               mask: BoolArray, r: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Measurement update of each model (eqs. (3)–(5)) and of the mode probabilities.

    ``z`` (N, 2), ``mask`` (N,) (a row with NaN has no measurement), ``r`` (N, 2)."""
    xo = x.copy()
    Po = P.copy()
    mo = mu.copy()
    for t in range(x.shape[0]):
        if not mask[t] or z[t, 0] != z[t, 0] or z[t, 1] != z[t, 1]:
            continue
        loglik = np.zeros(2)
        for j in range(2):
            for ax in range(2):
                a, b, c = P[t, j, ax, 0], P[t, j, ax, 1], P[t, j, ax, 2]
                s = a + r[t, ax]
                ka, kb = a / s, b / s
                nu = z[t, ax] - x[t, j, ax]
                loglik[j] += -0.5 * (nu * nu / s + math.log(2.0 * math.pi * s))
                xo[t, j, ax] = x[t, j, ax] + ka * nu  # eq. (4)
                xo[t, j, 2 + ax] = x[t, j, 2 + ax] + kb * nu
                Po[t, j, ax, 0] = a * (1.0 - ka)  # eq. (5)
                Po[t, j, ax, 1] = b * (1.0 - ka)
                Po[t, j, ax, 2] = c - b * kb
        top = max(loglik[0], loglik[1])
        w0 = mu[t, 0] * math.exp(loglik[0] - top)
        w1 = mu[t, 1] * math.exp(loglik[1] - top)
        mo[t, 0] = w0 / (w0 + w1)
        mo[t, 1] = 1.0 - mo[t, 0]
    return xo, Po, mo


@kernel
def imm_init(xy: FloatArray, r: FloatArray, vel_var: FloatArray, pi: FloatArray
             ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """New tracks at ``xy`` (K, 2) with zero velocity: both models start at ``P₀ = diag(r,
    vel_var)`` per axis (``r``, ``vel_var``: (K, 2)), the modes at their long-run shares
    under ``pi``."""
    k = xy.shape[0]
    x = np.zeros((k, 2, 4))
    P = np.zeros((k, 2, 2, 3))
    mu = np.empty((k, 2))
    stationary = pi[1, 0] / (pi[0, 1] + pi[1, 0])
    for t in range(k):
        for j in range(2):
            x[t, j, 0], x[t, j, 1] = xy[t, 0], xy[t, 1]
            for ax in range(2):
                P[t, j, ax, 0] = r[t, ax]
                P[t, j, ax, 2] = vel_var[t, ax]
        mu[t, 0], mu[t, 1] = stationary, 1.0 - stationary
    return x, P, mu


@kernel
def imm_combine(x: FloatArray, P: FloatArray, mu: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The moment-matched mixture: ``x`` (N, 4) and per-axis ``(a, b, c)`` (N, 2, 3)."""
    n = x.shape[0]
    xc = np.empty((n, 4))
    Pc = np.empty((n, 2, 3))
    for t in range(n):
        w0, w1 = mu[t, 0], mu[t, 1]
        for k in range(4):
            xc[t, k] = w0 * x[t, 0, k] + w1 * x[t, 1, k]
        for ax in range(2):
            d0p, d0v = x[t, 0, ax] - xc[t, ax], x[t, 0, 2 + ax] - xc[t, 2 + ax]
            d1p, d1v = x[t, 1, ax] - xc[t, ax], x[t, 1, 2 + ax] - xc[t, 2 + ax]
            Pc[t, ax, 0] = w0 * (P[t, 0, ax, 0] + d0p * d0p) + w1 * (P[t, 1, ax, 0] + d1p * d1p)
            Pc[t, ax, 1] = w0 * (P[t, 0, ax, 1] + d0p * d0v) + w1 * (P[t, 1, ax, 1] + d1p * d1v)
            Pc[t, ax, 2] = w0 * (P[t, 0, ax, 2] + d0v * d0v) + w1 * (P[t, 1, ax, 2] + d1v * d1v)
    return xc, Pc


class KalmanIMMPredictor:
    """``kalman-imm`` (implements :class:`mvtrack.filters.base.Predictor`).

    Parameters
    ----------
    q, q_manoeuvre : float
        White-acceleration variance of the steady and the manoeuvring model (px²/frame⁴),
        for tracks given none of their own.
    r : float
        Measurement-noise variance (px²).
    vel_var : float
        Initial velocity variance (px²/frame²).
    switch : (float, float)
        Probability per frame of leaving the steady and the manoeuvring mode.
    """

    name = "kalman-imm"
    noise_per_track = True

    def __init__(self, q: float = 0.1, q_manoeuvre: float = 10.0, r: float = 1.0,
                 vel_var: float = 25.0, switch: tuple[float, float] = (0.05, 0.2)) -> None:
        self.q = check_positive("q", q)
        self.q_manoeuvre = check_positive("q_manoeuvre", q_manoeuvre)
        self.r = check_positive("r", r)
        self.vel_var = check_positive("vel_var", vel_var)
        self.switch = (float(switch[0]), float(switch[1]))

    def transitions(self) -> FloatArray:
        """Π (2, 2) per frame."""
        a, b = self.switch
        return np.array([[1.0 - a, a], [b, 1.0 - b]])

    def _noise(self, value: FloatArray | None, default: float, n: int) -> FloatArray:
        if value is None:
            return np.full((n, 2), default)
        return np.asarray(value, dtype=np.float64).reshape(n, 2)

    def init(self, xy: FloatArray, r: FloatArray | None = None,
             vel_var: FloatArray | None = None) -> IMMState:
        """New tracks at ``xy`` (K, 2), zero velocity, both models alike, mostly steady."""
        xy = np.ascontiguousarray(check_xy("xy", xy))
        k = xy.shape[0]
        return IMMState(*imm_init(xy, self._noise(r, self.r, k),
                                  self._noise(vel_var, self.vel_var, k), self.transitions()))

    def predict(self, state: IMMState, q: FloatArray | None = None,
                q_manoeuvre: FloatArray | None = None) -> IMMState:
        """Mixing and time update (``q``, ``q_manoeuvre``: (N, 2) per track and axis)."""
        n = state.x.shape[0]
        qq = np.empty((n, 2, 2))
        qq[:, 0] = self._noise(q, self.q, n)
        qq[:, 1] = self._noise(q_manoeuvre, self.q_manoeuvre, n)
        return IMMState(*imm_predict(state.x, state.P, state.mu, qq, self.transitions()))

    def update(self, state: IMMState, z: FloatArray, mask: BoolArray,
               r: FloatArray | None = None) -> IMMState:
        """Measurement update; rows with ``mask`` False or NaN keep the prediction."""
        n = state.x.shape[0]
        z, mask = check_shapes(z, mask, n)
        return IMMState(*imm_update(state.x, state.P, state.mu, z, mask,
                                    np.ascontiguousarray(self._noise(r, self.r, n))))

    def _combined(self, state: IMMState) -> tuple[FloatArray, FloatArray]:
        return imm_combine(state.x, state.P, state.mu)

    def position(self, state: IMMState) -> FloatArray:
        """Combined position (N, 2)."""
        return self._combined(state)[0][:, :2]

    def velocity(self, state: IMMState) -> FloatArray:
        """Combined velocity (N, 2), px/frame."""
        return self._combined(state)[0][:, 2:]

    def position_cov(self, state: IMMState) -> FloatArray:
        """Combined position covariance (N, 2, 2), ``diag(a_x, a_y)``."""
        Pc = self._combined(state)[1]
        out = np.zeros((state.x.shape[0], 2, 2))
        out[:, 0, 0], out[:, 1, 1] = Pc[:, 0, 0], Pc[:, 1, 0]
        return out

    def innovation_cov(self, state: IMMState, r: FloatArray | None = None) -> FloatArray:
        """``diag(a_x + r_x, a_y + r_y)`` of the combined prediction."""
        out = self.position_cov(state)
        rr = self._noise(r, self.r, state.x.shape[0])
        out[:, 0, 0] += rr[:, 0]
        out[:, 1, 1] += rr[:, 1]
        return out
