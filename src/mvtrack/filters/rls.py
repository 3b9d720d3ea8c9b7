"""RLS adaptive transversal predictor, eqs. (10)–(15) of paper 1, batched.

A batch of ``B`` independent predictors (one per target and axis) is an :class:`RLSState`:
weights ``w`` (B, M), inverse-correlation matrices ``P`` (B, M, M) and the delay line
``taps`` (B, M) holding the last M observations, newest first, ``[y_n, …, y_{n−M+1}]``.

One step with the new observation ``y_n`` (SPEC §1.3), with ``ỹ_n = [y_{n−1} … y_{n−M}]ᵀ``
the delay line *before* the step:

.. math::
    k_n = \\frac{P_{n-1}\\tilde y_n}{1 + \\tilde y_n^T P_{n-1} \\tilde y_n} \\quad (12) \\qquad
    \\alpha_n = y_n - \\hat w_{n-1}^T \\tilde y_n \\quad (13) \\\\
    \\hat w_n = \\hat w_{n-1} + \\alpha_n k_n \\quad (14) \\qquad
    P_n = \\lambda^{-1} P_{n-1} - \\lambda^{-1} k_n \\tilde y_n^T P_{n-1} \\quad (15)

implemented exactly as printed. Eq. (12) lacks the λ⁻¹ of the textbook form; that is not an
error in effect (E1.1): the printed recursion is standard exponentially weighted RLS started
from ``P₀^std = λ P₀``, and its ``P_n`` is ``λ⁻¹`` times the standard one. Equivalently
(matrix-inversion lemma) ``P_n⁻¹ = λ (P_{n−1}⁻¹ + ỹ_n ỹ_nᵀ)``, so

.. math::
    P_n^{-1} = \\lambda^n c^{-1} I + \\sum_{i=1}^{n} \\lambda^{n-i+1} \\tilde y_i \\tilde y_i^T,
    \\qquad
    \\hat w_n = \\Big(\\lambda^{n-1} c^{-1} I + \\sum_{i=1}^{n} \\lambda^{n-i}
    \\tilde y_i \\tilde y_i^T\\Big)^{-1} \\sum_{i=1}^{n} \\lambda^{n-i} \\tilde y_i y_i ,

the exponentially weighted, regularised least-squares solution (for λ = 1 the ridge solution
``(Σ ỹỹᵀ + c⁻¹I)⁻¹ Σ ỹ y``).

The one-step-ahead prediction (E1.5) is ``ŷ_{n+1|n} = ŵ_nᵀ [y_n … y_{n−M+1}]ᵀ``; samples
before the first are 0 (SPEC §1.3 [R]) unless the delay line is initialised otherwise.

**Guard against the blow-up of P** (our addition, not in the paper). With λ < 1 and input that
does not excite every direction (a stopped vehicle: the same position for thousands of frames,
so every ỹ is parallel to ``[1, …, 1]``) eq. (15) multiplies ``P`` by λ⁻¹ in the unexcited
directions at every step: after 10⁶ frames at λ = 0.98 that is 0.98^(−10⁶), an overflow. We
bound the trace: when the λ⁻¹-scaled matrix of eq. (15) would have ``tr P_n > trace_max``
(default ``10 · c · M``, ten times the trace of ``P₀``), that step is taken without
forgetting, ``P_n = P_{n−1} − k_n ỹ_nᵀ P_{n−1}`` (λ = 1 for that step). The trace then never
exceeds ``trace_max`` (the λ = 1 step cannot increase it), the weights keep their meaning,
and once the target moves again the large ``P`` in the new directions makes the predictor
re-adapt quickly (like a covariance reset). In ordinary exciting use ``tr P`` stays orders of
magnitude below the bound and the recursion is exactly eqs. (12)–(15). ``P`` is symmetrised
after every step, and as a last-resort safety net a row whose ``P`` has become non-finite or
has a non-positive diagonal entry through rounding (extremely ill-conditioned, noise-free
input of large magnitude) is reset to ``c I`` (a covariance reset).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray
from mvtrack.filters.models import check_positive

__all__ = ["RLSState", "check_params", "init", "predict", "update"]


@dataclass(frozen=True)
class RLSState:
    """State of ``B`` RLS predictors.

    Attributes
    ----------
    w : ndarray (B, M)
        Weights ŵ_n.
    P : ndarray (B, M, M)
        The matrix P_n of eq. (15) (λ⁻¹ times the inverse weighted correlation matrix, E1.1).
    taps : ndarray (B, M)
        The delay line ``[y_n, …, y_{n−M+1}]``, newest first.
    """

    w: FloatArray
    P: FloatArray
    taps: FloatArray


def check_params(M: int, lam: float, c: float) -> tuple[int, float, float]:
    """Validate the RLS parameters: ``M ≥ 1`` (int), ``0 < λ ≤ 1``, ``c > 0``."""
    if isinstance(M, bool) or not isinstance(M, int | np.integer) or M < 1:
        raise ValueError(f"M (number of taps) must be an integer >= 1, got {M!r}")
    try:
        lam_f = float(lam)
    except (TypeError, ValueError):
        raise ValueError(f"lam (forgetting factor) must be in (0, 1], got {lam!r}") from None
    if not (0.0 < lam_f <= 1.0):
        raise ValueError(f"lam (forgetting factor) must be in (0, 1], got {lam!r}")
    return int(M), lam_f, check_positive("c", c)


def default_trace_max(M: int, c: float) -> float:
    """The default bound on ``tr P``: ten times the trace ``c·M`` of ``P₀``."""
    return 10.0 * c * M


def init(
    batch: int, M: int = 3, c: float = 100.0, taps: FloatArray | None = None
) -> RLSState:
    """``batch`` fresh predictors: ``ŵ₀ = 0``, ``P₀ = c·I`` (SPEC §1.3).

    Parameters
    ----------
    batch : int
        Number of predictors B.
    M : int
        Number of taps (paper: 3).
    c : float
        Initial ``P₀ = c I`` (SPEC [R]: 100).
    taps : ndarray (B, M), optional
        Initial delay line (newest first); zeros by default (samples before the first are 0).
    """
    M, _, c = check_params(M, 1.0, c)
    if isinstance(batch, bool) or not isinstance(batch, int | np.integer) or batch < 0:
        raise ValueError(f"batch must be an integer >= 0, got {batch!r}")
    if taps is None:
        t = np.zeros((batch, M))
    else:
        t = np.array(taps, dtype=np.float64)
        if t.shape != (batch, M):
            raise ValueError(f"taps must have shape ({batch}, {M}), got {t.shape}")
        if not np.all(np.isfinite(t)):
            raise ValueError("taps holds NaN or infinite values")
    P = np.zeros((batch, M, M))
    P[:, np.arange(M), np.arange(M)] = c
    return RLSState(w=np.zeros((batch, M)), P=P, taps=t)


def predict(state: RLSState) -> FloatArray:
    """One-step-ahead predictions ``ŷ_{n+1|n} = ŵ_nᵀ [y_n … y_{n−M+1}]ᵀ`` (B,), E1.5."""
    return np.einsum("bm,bm->b", state.w, state.taps)


def update(
    state: RLSState,
    y: FloatArray,
    lam: float = 0.98,
    mask: BoolArray | None = None,
    trace_max: float | None = None,
    c: float = 100.0,
) -> tuple[RLSState, FloatArray]:
    """Feed observation ``y_n`` (B,) to every predictor: eqs. (12)–(15) of paper 1.

    Parameters
    ----------
    state : RLSState
        State after step n−1.
    y : ndarray (B,)
        New observations; NaN/inf entries are missing.
    lam : float
        Forgetting factor λ in (0, 1] (SPEC [R]: 0.98).
    mask : ndarray (B,) of bool, optional
        False for predictors without an observation this step.
    trace_max : float, optional
        Bound on ``tr P`` (see the module docstring); default ``10 · c · M``. Pass ``np.inf``
        to disable the guard.
    c : float
        The ``P₀ = c I`` the predictors started from; only sets the default ``trace_max``.

    Returns
    -------
    state : RLSState
        State after step n. Where the observation is missing the weights and ``P`` are kept
        and the prediction ``ŵᵀỹ`` enters the delay line in place of the observation.
    alpha : ndarray (B,)
        A-priori errors α_n (eq. 13); NaN where the observation is missing.
    """
    _, lam, _ = check_params(1, lam, 1.0)
    w, P, u = state.w, state.P, state.taps
    B, M = w.shape
    y = np.asarray(y, dtype=np.float64)
    if y.shape != (B,):
        raise ValueError(f"y must have shape ({B},), got {y.shape}")
    ok = np.isfinite(y)
    if mask is not None:
        mask = np.asarray(mask)
        if mask.shape != (B,) or mask.dtype != np.bool_:
            raise ValueError(f"mask must be a boolean array of shape ({B},), got {mask.shape}")
        ok &= mask
    tmax = default_trace_max(M, c) if trace_max is None else float(trace_max)
    if not tmax > 0:
        raise ValueError(f"trace_max must be > 0, got {trace_max!r}")

    y_hat = np.einsum("bm,bm->b", w, u)  # ŵ_{n−1}ᵀ ỹ_n, the prediction of y_n (E1.5)
    alpha = np.where(ok, y, y_hat) - y_hat  # eq. (13)
    Pu = np.einsum("bij,bj->bi", P, u)  # P_{n−1} ỹ_n
    k = Pu / (1.0 + np.einsum("bi,bi->b", u, Pu))[:, None]  # eq. (12)
    w_new = w + alpha[:, None] * k  # eq. (14)
    uP = np.einsum("bi,bij->bj", u, P)  # ỹ_nᵀ P_{n−1}
    P1 = P - k[:, :, None] * uP[:, None, :]  # P_{n−1} − k ỹᵀ P_{n−1}
    P1 = 0.5 * (P1 + np.swapaxes(P1, 1, 2))
    tr = np.trace(P1, axis1=1, axis2=2)
    forget = tr / lam <= tmax  # guard: skip forgetting where tr P would exceed trace_max
    P_new = np.where(forget[:, None, None], P1 / lam, P1)  # eq. (15)
    # safety net: a P that lost positive diagonal / finiteness in rounding is reset to c I
    diag = np.diagonal(P_new, axis1=1, axis2=2)
    broken = ~np.all(np.isfinite(P_new), axis=(1, 2)) | np.any(diag <= 0.0, axis=1)
    if np.any(broken):
        P_new = np.where(broken[:, None, None], c * np.eye(M), P_new)
    w_new = np.where(ok[:, None], w_new, w)
    P_new = np.where(ok[:, None, None], P_new, P)
    taps = np.concatenate([np.where(ok, y, y_hat)[:, None], u[:, :-1]], axis=1)
    return RLSState(w=w_new, P=P_new, taps=taps), np.where(ok, alpha, np.nan)
