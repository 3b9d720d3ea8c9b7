"""Fast kernels for the per-axis filters the tracker runs every frame.

Same mathematics as :mod:`mvtrack.filters.kalman` and :mod:`mvtrack.filters.rls`, for the
special cases the predictors use, written so that NumPy runs long contiguous loops:

* **Component layout.** A batch of ``B`` filters is held component-first: the state as an
  array ``(n, B)``, the symmetric covariance packed as its upper triangle ``(n(n+1)/2, B)``
  (:func:`packed_index`). Every scalar of the closed-form equations is then one contiguous
  vector of length B, and each arithmetic step is one vectorised operation (no per-filter
  Python loop; the Python loops below run over the few matrix *components*).
* **Closed forms.** ``F P Fᵀ`` is expanded term by term, skipping zero entries of ``F`` and
  multiplications by one. The per-axis measurement ``H = [1, 0, …]`` selects the position,
  so the update is the rank-1 correction ``P − P h hᵀ P / S`` with the scalar ``S = P₀₀ + r``
  (algebraically eq. (5) of paper 1; ``P₀₀`` stays ``P₀₀ r / S > 0``).
* **Chunks.** Large batches are processed in chunks of
  :data:`~mvtrack.filters.layout.CHUNK` filters so the temporaries stay in cache; the results
  are identical (every filter is independent).

The layout (packing, chunks) is :mod:`mvtrack.filters.layout`; the RLS kernel
:func:`rls_step` is :mod:`mvtrack.filters.fast_rls` (both re-exported here).

The kernels do not validate their input (the predictors do) and never modify their arguments.
``tests/test_fast.py`` pins them equal to the generic functions.
"""

from __future__ import annotations

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray
from mvtrack.filters.fast_rls import rls_step
from mvtrack.filters.layout import CHUNK, chunked, finite, lincomb, pack, packed_index, unpack

__all__ = [
    "CHUNK",
    "kf_axis_predict",
    "kf_axis_update",
    "kf_select_update",
    "pack",
    "packed_index",
    "rls_step",
    "unpack",
]


def kf_axis_predict(
    x: FloatArray, p: FloatArray, F: FloatArray, Q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Eqs. (6)–(7) of paper 1 for ``B`` filters in component layout.

    .. math::
        \\bar x = F \\hat x \\quad (6) \\qquad \\bar P = F P F^T + Q \\quad (7)

    Parameters
    ----------
    x : ndarray (n, B)
        States, component-first.
    p : ndarray (n(n+1)/2, B)
        Packed covariances.
    F, Q : ndarray (n, n)
        Shared transition and process-noise matrices.

    Returns
    -------
    x_pred : ndarray (n, B)
    p_pred : ndarray (n(n+1)/2, B)
    """
    n, B = x.shape
    idx = packed_index(n)
    x_out = np.empty_like(x)
    p_out = np.empty_like(p)

    # which entries A_il of A = F P some upper-triangle P'_ij (j ≥ i) needs
    need = [sorted({ll for j in range(i, n) for ll in range(n) if F[j, ll] != 0.0})
            for i in range(n)]
    n_tmp = 1 + sum(len(nd) for nd in need)

    def kernel(sc: list[FloatArray], xc: FloatArray, pc: FloatArray, xo: FloatArray,
               po: FloatArray) -> None:
        tmp, free = sc[0], iter(sc[1:])
        for i in range(n):  # eq. (6)
            lincomb([(F[i, k], xc[k]) for k in range(n) if F[i, k] != 0.0], xo[i], tmp)
        A: dict[tuple[int, int], FloatArray] = {}
        for i in range(n):
            for ll in need[i]:
                terms = [(F[i, k], pc[idx[k, ll]]) for k in range(n) if F[i, k] != 0.0]
                if len(terms) == 1 and terms[0][0] == 1.0:
                    A[i, ll] = terms[0][1]
                else:
                    A[i, ll] = next(free)
                    lincomb(terms, A[i, ll], tmp)
        for i in range(n):  # eq. (7): P' = A Fᵀ + Q, upper triangle
            for j in range(i, n):
                out = po[idx[i, j]]
                lincomb([(F[j, ll], A[i, ll]) for ll in range(n) if F[j, ll] != 0.0], out, tmp)
                if Q[i, j] != 0.0:
                    out += Q[i, j]

    chunked(kernel, [x, p, x_out, p_out], B, n_tmp)
    return x_out, p_out


def kf_axis_update(
    x: FloatArray, p: FloatArray, z: FloatArray, r: float, ok: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Eqs. (3)–(5) of paper 1 with ``H = [1, 0, …]`` and ``R = r``, component layout.

    .. math::
        S = P_{00} + r,\\quad K = P_{:,0} / S \\quad (3) \\qquad
        \\hat x = \\bar x + K (z - \\bar x_0) \\quad (4) \\qquad
        P = \\bar P - K K^T S \\quad (5)

    Parameters
    ----------
    x : ndarray (n, B)
    p : ndarray (n(n+1)/2, B)
    z : ndarray (B,)
        Measurements (anything, even NaN, where ``ok`` is False).
    r : float
        Measurement-noise variance.
    ok : ndarray (B,) of bool
        Filters that got a measurement; the others are returned unchanged.
    """
    n, B = x.shape
    idx = packed_index(n)
    x_out = np.empty_like(x)
    p_out = np.empty_like(p)
    miss = ~(ok & finite(z))  # a missing measurement never enters the arithmetic

    def kernel(sc: list[FloatArray], xi: FloatArray, pi: FloatArray, zc: FloatArray,
               mc: BoolArray, xo: FloatArray, po: FloatArray) -> None:
        g, nu, k = sc[0], sc[1], sc[2:]
        np.add(pi[idx[0, 0]], r, out=g)  # eq. (3): S = P₀₀ + r
        np.divide(1.0, g, out=g)
        if any_miss:
            np.copyto(g, 0.0, where=mc)  # zero gain where there is no measurement
        np.subtract(zc, xi[0], out=nu)  # innovation z − H x̄
        if any_miss:
            np.copyto(nu, 0.0, where=mc)
        nu *= g
        for i in range(n):  # eq. (3): K_i = P_0i / S
            np.multiply(pi[idx[0, i]], g, out=k[i])
        for i in range(n):  # eq. (4): x_i + P_0i ν / S
            np.multiply(pi[idx[0, i]], nu, out=xo[i])
            xo[i] += xi[i]
        for i in range(n):  # eq. (5): P_ij − K_i P_0j
            for j in range(i, n):
                out = po[idx[i, j]]
                np.multiply(k[i], pi[idx[0, j]], out=out)
                np.subtract(pi[idx[i, j]], out, out=out)

    any_miss = bool(miss.any())
    chunked(kernel, [x, p, z, miss, x_out, p_out], B, 2 + n)
    return x_out, p_out


def kf_select_update(
    x: FloatArray, p: FloatArray, z: FloatArray, R: FloatArray, ok: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Eqs. (3)–(5) of paper 1 for a measurement of the first ``m`` ≤ 2 state components.

    ``H = [I_m 0]`` (the coupled model: ``z = [x, y]``), so ``S = P[:m, :m] + R`` is at most
    2×2 and is inverted in closed form.

    .. math::
        K = P H^T S^{-1} \\quad (3) \\qquad \\hat x = \\bar x + K (z - H \\bar x) \\quad (4)
        \\qquad P = \\bar P - K H \\bar P \\quad (5)

    Parameters
    ----------
    x : ndarray (n, B)
    p : ndarray (n(n+1)/2, B)
    z : ndarray (m, B)
    R : ndarray (m, m)
    ok : ndarray (B,) of bool
        Filters that got a measurement (rows of z with NaN count as missing).
    """
    n, B = x.shape
    m = z.shape[0]
    if m not in (1, 2):
        raise ValueError(f"kf_select_update handles 1 or 2 measured components, got {m}")
    idx = packed_index(n)
    x_out = np.empty_like(x)
    p_out = np.empty_like(p)
    miss = ~ok
    for a in range(m):
        miss = miss | ~finite(z[a])

    def kernel(sc: list[FloatArray], xi: FloatArray, pin: FloatArray, zc: FloatArray,
               mc: BoolArray, xo: FloatArray, po: FloatArray) -> None:
        np.copyto(xo, xi)
        np.copyto(po, pin)
        tmp, det = sc[0], sc[1]
        inv = sc[2:5]  # S⁻¹ entries 00, 01, 11
        nu = sc[5:7]
        HP = [[sc[7 + a * n + j] for j in range(n)] for a in range(m)]
        K = [[sc[7 + 2 * n + i * m + a] for a in range(m)] for i in range(n)]
        for a in range(m):  # rows of P̄ the update subtracts from (H P̄), before changing P
            for j in range(n):
                np.copyto(HP[a][j], po[idx[a, j]])
        if m == 1:
            np.add(po[idx[0, 0]], R[0, 0], out=inv[0])
            np.divide(1.0, inv[0], out=inv[0])
            np.copyto(inv[0], 0.0, where=mc)
        else:
            s00 = po[idx[0, 0]] + R[0, 0]
            s01 = po[idx[0, 1]] + R[0, 1]
            s11 = po[idx[1, 1]] + R[1, 1]
            np.multiply(s00, s11, out=det)
            np.multiply(s01, s01, out=tmp)
            det -= tmp
            np.divide(1.0, det, out=det)
            np.copyto(det, 0.0, where=mc)  # zero gain where there is no measurement
            np.multiply(s11, det, out=inv[0])
            np.multiply(s01, det, out=inv[1])
            np.negative(inv[1], out=inv[1])
            np.multiply(s00, det, out=inv[2])
        sinv = [[inv[0]]] if m == 1 else [[inv[0], inv[1]], [inv[1], inv[2]]]
        for i in range(n):  # eq. (3): K = P̄ Hᵀ S⁻¹, P̄Hᵀ = (HP̄)ᵀ
            for a in range(m):
                np.multiply(HP[0][i], sinv[0][a], out=K[i][a])
                for b in range(1, m):
                    np.multiply(HP[b][i], sinv[b][a], out=tmp)
                    K[i][a] += tmp
        for a in range(m):  # innovation
            np.subtract(zc[a], xo[a], out=nu[a])
            np.copyto(nu[a], 0.0, where=mc)
        for i in range(n):  # eq. (4)
            for a in range(m):
                np.multiply(K[i][a], nu[a], out=tmp)
                xo[i] += tmp
        for i in range(n):  # eq. (5): P −= K (H P̄)
            for j in range(i, n):
                for a in range(m):
                    np.multiply(K[i][a], HP[a][j], out=tmp)
                    po[idx[i, j]] -= tmp

    chunked(kernel, [x, p, z, miss, x_out, p_out], B, 7 + 2 * n + n * m)
    return x_out, p_out
