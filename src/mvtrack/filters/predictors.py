"""The predictors the tracker uses: ``kalman-ca``, ``kalman-cv``, ``kalman-coupled``, ``rls``.

Each class implements :class:`mvtrack.filters.base.Predictor`: a stateless object holding
parameters, and a per-track state that is a frozen dataclass of arrays with leading dimension
``N`` (one row per track), so :func:`mvtrack.types.take_rows` /
:func:`mvtrack.types.concat_rows` grow and shrink it. Units are pixels and frames (Δt = 1 frame).

=================  ==========================================================================
name               method
=================  ==========================================================================
``kalman-ca``      per-axis constant-acceleration KF, paper 1 eqs. (3)–(9)
``kalman-cv``      per-axis constant-velocity KF in closed form (:mod:`mvtrack.filters.cv`)
``kalman-coupled`` one 2-D KF per track, x and y in one state (full 2×2 position covariance)
``rls``            per-axis RLS adaptive transversal predictor, paper 1 eqs. (10)–(15)
=================  ==========================================================================

Per-axis filters run x and y as two filters of the same model (SPEC §1.1); their state holds
both axes in one array (``x`` of shape (N, 2, n)), so all tracks and both axes are advanced by
one vectorised call — no Python loop over tracks.

Initial covariances (documented reconstruction choices, SPEC E1.11): a new track starts at its
first measurement with zero velocity (and acceleration), and
``P₀ = diag(r, vel_var[, acc_var])`` per axis: the position is known to the measurement
variance ``r``, the velocity to ``vel_var`` (default 25 px²/frame², a 5 px/frame standard
deviation), the acceleration to ``acc_var`` (default 1 px²/frame⁴).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from mvtrack.filters import fast, rls
from mvtrack.filters.base import BoolArray, FloatArray, Predictor, check_xy, check_z_mask
from mvtrack.filters.cv import CVState, KalmanCVPredictor
from mvtrack.filters.models import (
    LinearModel,
    check_positive,
    constant_acceleration,
    coupled,
)

__all__ = [
    "PREDICTORS",
    "AxisKalmanState",
    "CVState",
    "CoupledKalmanPredictor",
    "KalmanCAPredictor",
    "KalmanCVPredictor",
    "KalmanState",
    "PerAxisKalmanPredictor",
    "RLSPredictor",
    "RLSPredictorState",
    "make_predictor",
]


def _diag2(a: FloatArray) -> FloatArray:
    """(N, 2) -> (N, 2, 2) diagonal matrices."""
    out = np.zeros((a.shape[0], 2, 2))
    out[:, 0, 0] = a[:, 0]
    out[:, 1, 1] = a[:, 1]
    return out


def _to_comp(a: FloatArray) -> FloatArray:
    """Logical (N, 2, K) -> component-first buffer (K, 2N); no copy if already laid out so."""
    N, _, K = a.shape
    return np.ascontiguousarray(np.transpose(a, (2, 1, 0))).reshape(K, 2 * N)


def _from_comp(buf: FloatArray, N: int) -> FloatArray:
    """Component-first buffer (K, 2N) -> logical (N, 2, K) view (memory stays component-first)."""
    return np.transpose(buf.reshape(buf.shape[0], 2, N), (2, 1, 0))


def _axes_flat(a: FloatArray) -> FloatArray:
    """(N, 2) -> (2N,) with all x values first, then all y values (the component order)."""
    return np.ascontiguousarray(a.T).reshape(-1)


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
        x, P = fast.kf_axis_predict(_to_comp(state.x), _to_comp(state.P), self.model.F,
                                    self.model.Q)
        return AxisKalmanState(x=_from_comp(x, N), P=_from_comp(P, N))

    def update(self, state: AxisKalmanState, z: FloatArray, mask: BoolArray) -> AxisKalmanState:
        """Measurement update, eqs. (3)–(5); rows with mask False or NaN keep the prediction."""
        N = state.x.shape[0]
        z, ok = check_z_mask(z, mask, N)
        x, P = fast.kf_axis_update(_to_comp(state.x), _to_comp(state.P), _axes_flat(z), self.r,
                                   np.concatenate([ok, ok]))
        return AxisKalmanState(x=_from_comp(x, N), P=_from_comp(P, N))

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
        return _diag2(state.P[:, :, 0])

    def innovation_cov(self, state: AxisKalmanState) -> FloatArray:
        """Diagonal innovation covariance (N, 2, 2): ``S = P[0, 0] + r`` per axis."""
        return _diag2(state.P[:, :, 0] + self.r)


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
        flat = _axes_flat(xy)
        taps = np.zeros((M, 2 * K)) if self.history == "zeros" else np.tile(flat, (M, 1))
        p0 = np.zeros((M * (M + 1) // 2, 2 * K))
        p0[np.diagonal(fast.packed_index(M))] = self.c
        w, p, taps, _ = fast.rls_step(np.zeros((M, 2 * K)), p0, taps, flat, self.lam,
                                      np.ones(2 * K, bool), self.trace_max, self.c)
        return RLSPredictorState(
            w=_from_comp(w, K),
            P=_from_comp(p, K),
            taps=_from_comp(taps, K),
            xy=xy.copy(),
            err_var=np.full((K, 2), self.r + self.vel_var),
            count=np.ones(K, dtype=np.int64),
        )

    def _rls_prediction(self, state: RLSPredictorState) -> FloatArray:
        """``ŵ_nᵀ [y_n … y_{n−M+1}]`` per axis, (N, 2) (E1.5)."""
        w, t = _to_comp(state.w), _to_comp(state.taps)
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
        fill = _axes_flat(state.xy)
        w, p, taps, _ = fast.rls_step(
            _to_comp(state.w), _to_comp(state.P), _to_comp(state.taps), _axes_flat(z),
            self.lam, np.concatenate([ok, ok]), self.trace_max, self.c, fill=fill,
        )
        err = np.where(ok[:, None], z, state.xy) - state.xy
        err_var = np.where(ok[:, None], (1 - self.beta) * state.err_var + self.beta * err**2,
                           state.err_var)
        return RLSPredictorState(
            w=_from_comp(w, N),
            P=_from_comp(p, N),
            taps=_from_comp(taps, N),
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
        return _diag2(np.maximum(state.err_var - self.r, self.min_var))

    def innovation_cov(self, state: RLSPredictorState) -> FloatArray:
        """``S = P̄ + r`` per axis, (N, 2, 2)."""
        return _diag2(np.maximum(state.err_var - self.r, self.min_var) + self.r)


#: predictor name -> class
PREDICTORS: dict[str, type] = {
    "kalman-ca": KalmanCAPredictor,
    "kalman-cv": KalmanCVPredictor,
    "kalman-coupled": CoupledKalmanPredictor,
    "rls": RLSPredictor,
}


def make_predictor(name: str, **params: Any) -> Predictor:
    """The predictor called ``name`` with constructor parameters ``params``.

    ``structured`` (paper 3's structured KF, :mod:`mvtrack.filters.structured`) is also
    accepted; it needs part measurements, so it is not in :data:`PREDICTORS`.

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the known names) or a parameter is bad.
    """
    if name == "structured":
        from mvtrack.filters.structured import StructuredPredictor

        return StructuredPredictor(**params)  # type: ignore[no-any-return]
    if name not in PREDICTORS:
        known = ", ".join([*PREDICTORS, "structured"])
        raise ValueError(f"unknown predictor {name!r}; choose one of: {known}")
    try:
        return PREDICTORS[name](**params)  # type: ignore[no-any-return]
    except TypeError as exc:
        raise ValueError(f"bad parameters for predictor {name!r}: {exc}") from None
