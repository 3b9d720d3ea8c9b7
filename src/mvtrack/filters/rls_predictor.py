"""``rls``: the per-axis RLS adaptive transversal predictor of paper 1, eqs. (10)–(15).

The pure functions are :mod:`mvtrack.filters.rls`; the per-frame kernel
:func:`mvtrack.filters.fast_rls.rls_step`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np

from mvtrack.filters import fast, rls
from mvtrack.filters.base import BoolArray, FloatArray, check_xy, check_z_mask
from mvtrack.filters.layout import axes_flat, diag2, from_components, to_components
from mvtrack.filters.models import (
    check_positive,
)

__all__ = ["RLSPredictor", "RLSPredictorState"]


@dataclass(frozen=True)
class RLSPredictorState:
    """State of ``N`` tracks for :class:`RLSPredictor` (two RLS filters per track, x and y).

    Attributes
    ----------
    w : ndarray (N, 2, M)
        Weights per axis.
    P : ndarray (N, 2, M(M+1)/2)
        The matrix P of eq. (15) per axis, packed upper triangle
        (:func:`mvtrack.filters.fast.unpack`).
    taps : ndarray (N, 2, M)
        Delay line per axis, newest first.
    xy : ndarray (N, 2)
        Current position: the prediction after ``predict``, the observation after ``update``.
    err_var : ndarray (N, 2)
        Running (EWMA) estimate of the a-priori error variance per axis.
    count : ndarray (N,) of int
        Number of observations received (for the warm-up).

    ``w``, ``P`` and ``taps`` are stored component-first in memory (see
    :class:`AxisKalmanState`).
    """

    w: FloatArray
    P: FloatArray
    taps: FloatArray
    xy: FloatArray
    err_var: FloatArray
    count: np.ndarray


class RLSPredictor:
    """``rls``: per-axis RLS adaptive transversal predictor, paper 1 eqs. (10)–(15).

    Parameters
    ----------
    M : int
        Number of taps (paper: 3).
    lam : float
        Forgetting factor λ in (0, 1] (SPEC [R]: 0.98).
    c : float
        ``P₀ = c I`` (SPEC [R]: 100).
    r : float
        Measurement-noise variance (px²): the part of the a-priori error variance that is
        measurement noise, ``S = P̄ + r``.
    vel_var : float
        Initial a-priori error variance above ``r`` (the first prediction does not know the
        velocity, like the KF's initial velocity variance).
    beta : float
        Weight of the newest squared error in the running estimate
        ``e ← (1 − β) e + β α²`` of the a-priori error variance (0 < β ≤ 1).
    min_var : float
        Floor of the position variance ``P̄ = max(e − r, min_var)``.
    warmup : int or None
        Until a track has this many observations its prediction is ``2 y_k − y_{k−1}``
        (``y_k`` after one), SPEC §1.1 [R]; default ``2 M``. 0 disables.
    history : {"zeros", "first"}
        Delay-line samples before the first observation: 0 (SPEC §1.3 [R]) or the first
        observation repeated.
    trace_max : float or None
        Bound on ``tr P`` (see :mod:`mvtrack.filters.rls`); default ``10 c M``.

    Notes
    -----
    RLS has no covariance of its own; ``position_cov`` is ``P̄ I₂`` and ``innovation_cov`` is
    ``(P̄ + r) I₂`` per axis from the running error variance. The error that feeds the
    running estimate is that of the position this predictor reported after ``predict`` (the
    warm-up extrapolation while warming up).
    """

    name = "rls"

    def __init__(
        self,
        M: int = 3,
        lam: float = 0.98,
        c: float = 100.0,
        r: float = 1.0,
        vel_var: float = 25.0,
        beta: float = 0.1,
        min_var: float = 0.5,
        warmup: int | None = None,
        history: Literal["zeros", "first"] = "zeros",
        trace_max: float | None = None,
    ) -> None:
        self.M, self.lam, self.c = rls.check_params(M, lam, c)
        self.r = check_positive("r", r)
        self.vel_var = check_positive("vel_var", vel_var)
        self.beta = check_positive("beta", beta)
        if self.beta > 1.0:
            raise ValueError(f"beta must be in (0, 1], got {beta!r}")
        self.min_var = check_positive("min_var", min_var)
        w = 2 * self.M if warmup is None else warmup
        if isinstance(w, bool) or not isinstance(w, int | np.integer) or w < 0:
            raise ValueError(f"warmup must be an integer >= 0, got {warmup!r}")
        self.warmup = int(w)
        if history not in ("zeros", "first"):
            raise ValueError(f"history must be 'zeros' or 'first', got {history!r}")
        self.history = history
        self.trace_max = (
            rls.default_trace_max(self.M, self.c) if trace_max is None
            else check_positive("trace_max", trace_max)
        )

    def init(self, xy: FloatArray) -> RLSPredictorState:
        """State of ``K`` new tracks whose first observation is ``xy`` (K, 2).

        The RLS filters start from ``ŵ₀ = 0``, ``P₀ = c I`` and take ``xy`` as their first
        observation (eqs. (12)–(15) with ỹ₁ the history).
        """
        xy = check_xy("xy", xy)
        if not np.all(np.isfinite(xy)):
            raise ValueError("xy holds NaN or infinite values")
        K, M = xy.shape[0], self.M
        flat = axes_flat(xy)
        taps = np.zeros((M, 2 * K)) if self.history == "zeros" else np.tile(flat, (M, 1))
        p0 = np.zeros((M * (M + 1) // 2, 2 * K))
        p0[np.diagonal(fast.packed_index(M))] = self.c
        w, p, taps, _ = fast.rls_step(np.zeros((M, 2 * K)), p0, taps, flat, self.lam,
                                      np.ones(2 * K, bool), self.trace_max, self.c)
        return RLSPredictorState(
            w=from_components(w, K),
            P=from_components(p, K),
            taps=from_components(taps, K),
            xy=xy.copy(),
            err_var=np.full((K, 2), self.r + self.vel_var),
            count=np.ones(K, dtype=np.int64),
        )

    def _rls_prediction(self, state: RLSPredictorState) -> FloatArray:
        """``ŵ_nᵀ [y_n … y_{n−M+1}]`` per axis, (N, 2) (E1.5)."""
        w, t = to_components(state.w), to_components(state.taps)
        y = w[0] * t[0]
        for i in range(1, self.M):
            y += w[i] * t[i]
        return y.reshape(2, -1).T

    def _extrapolation(self, state: RLSPredictorState) -> FloatArray:
        """Warm-up prediction ``2 y_n − y_{n−1}`` (``y_n`` for a one-sample track), (N, 2)."""
        t = state.taps
        if self.M < 2:
            return t[:, :, 0].copy()
        return np.where((state.count >= 2)[:, None], 2.0 * t[:, :, 0] - t[:, :, 1], t[:, :, 0])

    def predict(self, state: RLSPredictorState) -> RLSPredictorState:
        """Next-frame position: ``ŷ_{n+1|n} = ŵ_nᵀ[y_n … y_{n−M+1}]`` (E1.5) per axis, or the
        warm-up extrapolation ``2 y_n − y_{n−1}`` for tracks with fewer than ``warmup``
        observations (SPEC §1.1 [R])."""
        y_rls = self._rls_prediction(state)
        if self.warmup > 0:
            warm = (state.count < self.warmup)[:, None]
            y_rls = np.where(warm, self._extrapolation(state), y_rls)
        return replace(state, xy=y_rls)

    def update(
        self, state: RLSPredictorState, z: FloatArray, mask: BoolArray
    ) -> RLSPredictorState:
        """Feed the observations to the RLS filters, eqs. (12)–(15) of paper 1.

        Rows without an observation keep their weights and ``P``; the position reported by
        :meth:`predict` enters their delay line in place of the missing observation (the
        track coasts). The running error variance ``e ← (1 − β) e + β (z − ŷ)²`` uses the
        error of the reported prediction.
        """
        N = state.w.shape[0]
        z, ok = check_z_mask(z, mask, N)
        fill = axes_flat(state.xy)
        w, p, taps, _ = fast.rls_step(
            to_components(state.w), to_components(state.P), to_components(state.taps), axes_flat(z),
            self.lam, np.concatenate([ok, ok]), self.trace_max, self.c, fill=fill,
        )
        err = np.where(ok[:, None], z, state.xy) - state.xy
        err_var = np.where(ok[:, None], (1 - self.beta) * state.err_var + self.beta * err**2,
                           state.err_var)
        return RLSPredictorState(
            w=from_components(w, N),
            P=from_components(p, N),
            taps=from_components(taps, N),
            xy=taps[0].reshape(2, N).T.copy(),
            err_var=err_var,
            count=state.count + ok,
        )

    def covariance(self, state: RLSPredictorState) -> FloatArray:
        """Full matrices P of eq. (15), (N, 2, M, M)."""
        return fast.unpack(state.P, self.M)

    def position(self, state: RLSPredictorState) -> FloatArray:
        """Prediction after ``predict``; the newest observation after ``update``."""
        return state.xy.copy()

    def velocity(self, state: RLSPredictorState) -> FloatArray:
        """Predicted displacement per frame: ``ŷ_{n+1|n} − y_n`` (0 for a one-sample track)."""
        pred = self._rls_prediction(state)
        if self.warmup > 0:
            pred = np.where((state.count < self.warmup)[:, None], self._extrapolation(state), pred)
        return np.where((state.count >= 2)[:, None], pred - state.taps[:, :, 0], 0.0)

    def position_cov(self, state: RLSPredictorState) -> FloatArray:
        """``P̄ = max(e − r, min_var)`` per axis from the running error variance, (N, 2, 2)."""
        return diag2(np.maximum(state.err_var - self.r, self.min_var))

    def innovation_cov(self, state: RLSPredictorState) -> FloatArray:
        """``S = P̄ + r`` per axis, (N, 2, 2)."""
        return diag2(np.maximum(state.err_var - self.r, self.min_var) + self.r)
