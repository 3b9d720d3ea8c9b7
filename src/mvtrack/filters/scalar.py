"""Single-target, pure-Python versions of the KF and RLS steps of paper 1.

These are the reference "scalar code" of the paper's era: plain loops over matrix entries,
one target, one axis, written with nothing but ``+``, ``−``, ``×``, ``÷`` on the numbers they
are given. They serve three purposes:

* **Operation counts** (Table 1, SPEC X2): run them on a counting number type
  (:class:`mvtrack.experiments.complexity.Counted`) and every arithmetic operation of the
  implemented equations is counted — nothing typed in.
* **Pure-Python timing** (Table 2, SPEC X3).
* **Oracle** for the batched code: the tests run the batched kernels against them.

The KF is dense and general (any ``n``, any ``1×n`` ``H``), exactly eqs. (3)–(7) as printed;
the RLS step is the straightforward form of eqs. (12)–(15) with ``π = P ỹ`` (E1.9), and
optionally the trace guard of :mod:`mvtrack.filters.rls`.
"""

from __future__ import annotations

import math
from typing import Any

Matrix = list[list[Any]]
Vector = list[Any]

__all__ = ["kf_predict", "kf_update", "rls_predict", "rls_update"]


def kf_update(
    x: Vector, P: Matrix, z: Any, H: Vector, R: Any
) -> tuple[Vector, Matrix]:
    """Eqs. (3)–(5) of paper 1 for one target, scalar measurement, dense arithmetic.

    .. math::
        K = \\bar P H^T (H \\bar P H^T + R)^{-1} \\;(3) \\quad
        \\hat x = \\bar x + K (z - H \\bar x) \\;(4) \\quad
        P = (I - K H) \\bar P \\;(5)
    """
    n = len(x)
    PHt = [_dot(P[i], H) for i in range(n)]  # eq. (3): P̄Hᵀ
    s = _dot(H, PHt) + R  # eq. (3): HP̄Hᵀ + R
    s_inv = 1 / s  # eq. (3): the one scalar inversion
    K = [PHt[i] * s_inv for i in range(n)]  # eq. (3)
    nu = z - _dot(H, x)  # eq. (4): innovation
    x_post = [x[i] + K[i] * nu for i in range(n)]  # eq. (4)
    IKH = [[(1 if i == j else 0) - K[i] * H[j] for j in range(n)] for i in range(n)]  # eq. (5)
    P_post = [[_dot(IKH[i], [P[k][j] for k in range(n)]) for j in range(n)] for i in range(n)]
    return x_post, P_post


def kf_predict(x: Vector, P: Matrix, F: Matrix, Q: Matrix) -> tuple[Vector, Matrix]:
    """Eqs. (6)–(7) of paper 1 for one target, dense arithmetic.

    .. math::
        \\bar x = F \\hat x \\;(6) \\qquad \\bar P = F P F^T + Q \\;(7)
    """
    n = len(x)
    x_pred = [_dot(F[i], x) for i in range(n)]  # eq. (6)
    FP = [[_dot(F[i], [P[k][j] for k in range(n)]) for j in range(n)] for i in range(n)]
    P_pred = [[_dot(FP[i], F[j]) + Q[i][j] for j in range(n)] for i in range(n)]  # eq. (7)
    return x_pred, P_pred


def rls_update(
    w: Vector, P: Matrix, u: Vector, y: Any, inv_lam: Any, trace_max: float = math.inf
) -> tuple[Vector, Matrix, Vector, Any]:
    """Eqs. (12)–(15) of paper 1 for one predictor; ``u`` is the delay line ỹ_n (newest first).

    .. math::
        \\pi = P_{n-1}\\tilde y_n,\\; k_n = \\pi / (1 + \\tilde y_n^T \\pi) \\;(12) \\quad
        \\alpha_n = y_n - \\hat w_{n-1}^T \\tilde y_n \\;(13) \\\\
        \\hat w_n = \\hat w_{n-1} + \\alpha_n k_n \\;(14) \\quad
        P_n = \\lambda^{-1} (P_{n-1} - k_n \\pi^T) \\;(15)

    ``inv_lam`` is λ⁻¹ (a constant, computed once). With a finite ``trace_max`` the step is
    taken without forgetting when ``tr P_n`` would exceed it (the guard of
    :mod:`mvtrack.filters.rls`).

    Returns
    -------
    w, P, u, alpha : new weights, P, delay line (with ``y`` shifted in) and a-priori error.
    """
    M = len(w)
    pi = [_dot(P[i], u) for i in range(M)]  # P ỹ (ỹᵀP = πᵀ, P symmetric)
    d = 1 + _dot(u, pi)  # eq. (12) denominator
    k = [pi[i] / d for i in range(M)]  # eq. (12)
    alpha = y - _dot(w, u)  # eq. (13)
    w = [w[i] + alpha * k[i] for i in range(M)]  # eq. (14)
    P1 = [[P[i][j] - k[i] * pi[j] for j in range(M)] for i in range(M)]  # eq. (15) bracket
    if trace_max < math.inf:
        tr = P1[0][0]
        for i in range(1, M):
            tr = tr + P1[i][i]
        if not tr * inv_lam <= trace_max:  # guard: no forgetting this step
            return w, P1, [y, *u[:-1]], alpha
    P = [[P1[i][j] * inv_lam for j in range(M)] for i in range(M)]  # eq. (15)
    return w, P, [y, *u[:-1]], alpha


def rls_predict(w: Vector, u: Vector) -> Any:
    """One-step-ahead prediction ``ŵ_nᵀ [y_n … y_{n−M+1}]`` (E1.5)."""
    return _dot(w, u)


def _dot(a: Vector, b: Vector) -> Any:
    acc = a[0] * b[0]
    for i in range(1, len(a)):
        acc = acc + a[i] * b[i]
    return acc
