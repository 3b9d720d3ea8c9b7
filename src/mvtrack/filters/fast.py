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
* **Chunks.** Large batches are processed in chunks of :data:`CHUNK` filters so the
  temporaries stay in cache; the results are identical (every filter is independent).

The kernels do not validate their input (the predictors do) and never modify their arguments.
``tests/test_fast.py`` pins them equal to the generic functions.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray

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

#: filters per chunk (keeps about 20 temporaries of CHUNK doubles in the L2/L3 cache)
CHUNK = 16384


def packed_index(n: int) -> np.ndarray:
    """``idx[i, j]``: row of component ``P_ij`` in the packed upper triangle (symmetric)."""
    idx = np.zeros((n, n), dtype=np.intp)
    k = 0
    for i in range(n):
        for j in range(i, n):
            idx[i, j] = idx[j, i] = k
            k += 1
    return idx


def pack(P: FloatArray) -> FloatArray:
    """Full symmetric matrices ``(…, n, n)`` -> packed upper triangles ``(…, n(n+1)/2)``."""
    n = P.shape[-1]
    iu = np.triu_indices(n)
    return P[..., iu[0], iu[1]]


def unpack(p: FloatArray, n: int) -> FloatArray:
    """Packed upper triangles ``(…, n(n+1)/2)`` -> full symmetric matrices ``(…, n, n)``."""
    return p[..., packed_index(n)]


def _chunked(fn: Callable[..., None], arrays: list[np.ndarray], B: int, n_scratch: int) -> None:
    """Call ``fn(scratch, *slices)`` on column slices ``[s:s+CHUNK]`` of every array.

    ``scratch`` is a list of ``n_scratch`` float vectors of the chunk's length, reused across
    chunks (no allocation per chunk).
    """
    size = min(B, CHUNK)
    buf = np.empty((n_scratch, size), dtype=arrays[0].dtype)
    for s in range(0, B, CHUNK):
        e = min(s + CHUNK, B)
        scratch = [row[: e - s] for row in buf]
        fn(scratch, *[a[..., s:e] for a in arrays])


def _finite(a: np.ndarray) -> BoolArray:
    """``np.isfinite`` for float arrays; all true for object arrays (counting numbers)."""
    if a.dtype == object:
        return np.ones(a.shape, dtype=bool)
    return np.isfinite(a)


def _lincomb(terms: list[tuple[float, FloatArray]], out: FloatArray, tmp: FloatArray) -> None:
    """``out[:] = Σ c·a`` over ``terms`` (zero coefficients already dropped; none empty)."""
    c0, a0 = terms[0]
    rest = terms[1:]
    if c0 == 1.0 and rest and rest[0][0] == 1.0:
        np.add(a0, rest[0][1], out=out)
        rest = rest[1:]
    elif c0 == 1.0 and rest:
        np.multiply(rest[0][1], rest[0][0], out=out)
        out += a0
        rest = rest[1:]
    elif c0 == 1.0:
        np.copyto(out, a0)
    else:
        np.multiply(a0, c0, out=out)
    for c, a in rest:
        if c == 1.0:
            out += a
        else:
            np.multiply(a, c, out=tmp)
            out += tmp


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
            _lincomb([(F[i, k], xc[k]) for k in range(n) if F[i, k] != 0.0], xo[i], tmp)
        A: dict[tuple[int, int], FloatArray] = {}
        for i in range(n):
            for ll in need[i]:
                terms = [(F[i, k], pc[idx[k, ll]]) for k in range(n) if F[i, k] != 0.0]
                if len(terms) == 1 and terms[0][0] == 1.0:
                    A[i, ll] = terms[0][1]
                else:
                    A[i, ll] = next(free)
                    _lincomb(terms, A[i, ll], tmp)
        for i in range(n):  # eq. (7): P' = A Fᵀ + Q, upper triangle
            for j in range(i, n):
                out = po[idx[i, j]]
                _lincomb([(F[j, ll], A[i, ll]) for ll in range(n) if F[j, ll] != 0.0], out, tmp)
                if Q[i, j] != 0.0:
                    out += Q[i, j]

    _chunked(kernel, [x, p, x_out, p_out], B, n_tmp)
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
    miss = ~(ok & _finite(z))  # a missing measurement never enters the arithmetic

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
    _chunked(kernel, [x, p, z, miss, x_out, p_out], B, 2 + n)
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
        miss = miss | ~_finite(z[a])

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

    _chunked(kernel, [x, p, z, miss, x_out, p_out], B, 7 + 2 * n + n * m)
    return x_out, p_out


def rls_step(
    w: FloatArray,
    p: FloatArray,
    taps: FloatArray,
    y: FloatArray,
    lam: float,
    ok: BoolArray,
    trace_max: float,
    c: float,
    fill: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Eqs. (12)–(15) of paper 1 for ``B`` predictors in component layout.

    Same step as :func:`mvtrack.filters.rls.update` (guard and safety net included).

    Parameters
    ----------
    w : ndarray (M, B)
        Weights.
    p : ndarray (M(M+1)/2, B)
        Packed P.
    taps : ndarray (M, B)
        Delay line, newest first (ỹ_n of this step).
    y : ndarray (B,)
        Observations (ignored where ``ok`` is False).
    lam, trace_max, c : float
        Forgetting factor, bound on ``tr P``, ``P₀ = c I`` (for the safety-net reset).
    ok : ndarray (B,) of bool
        Predictors with an observation; the others keep ``w`` and ``P`` and shift their
        prediction (or ``fill``) into the delay line.
    fill : ndarray (B,), optional
        What enters the delay line where ``ok`` is False; default the predictor's own
        prediction ``ŵᵀỹ``.

    Returns
    -------
    w, p, taps : the new state; alpha : ndarray (B,) the a-priori errors (0 where not ok).
    """
    M, B = w.shape
    idx = packed_index(M)
    w_out = np.empty_like(w)
    p_out = np.empty_like(p)
    taps_out = np.empty_like(taps)
    alpha = np.empty(B, dtype=w.dtype)
    y_in = np.asarray(y, dtype=w.dtype)
    miss = ~(ok & _finite(y_in))
    inv_lam = 1.0 / lam
    fill_in = y_in if fill is None else np.asarray(fill, dtype=w.dtype)
    use_fill = fill is not None
    diag = [int(idx[i, i]) for i in range(M)]

    def kernel(sc: list[FloatArray], wi: FloatArray, pin: FloatArray, u: FloatArray,
               yc: FloatArray, mc: BoolArray, fc: FloatArray, wo: FloatArray, po: FloatArray,
               to: FloatArray, al: FloatArray) -> None:
        d, yh, tmp, tr, k_i = sc[0], sc[1], sc[2], sc[3], sc[4]
        pi = sc[5 : 5 + M]
        for i in range(M):  # π = P_{n−1} ỹ_n
            np.multiply(pin[idx[i, 0]], u[0], out=pi[i])
            for j in range(1, M):
                np.multiply(pin[idx[i, j]], u[j], out=tmp)
                pi[i] += tmp
        np.multiply(u[0], pi[0], out=d)  # ỹᵀπ
        np.multiply(wi[0], u[0], out=yh)  # ŵ_{n−1}ᵀ ỹ_n
        for i in range(1, M):
            np.multiply(u[i], pi[i], out=tmp)
            d += tmp
            np.multiply(wi[i], u[i], out=tmp)
            yh += tmp
        d += 1.0
        np.divide(1.0, d, out=d)  # 1 / (1 + ỹᵀπ)
        np.subtract(yc, yh, out=al)  # eq. (13), α = y − ŵᵀỹ
        if any_miss:
            np.copyto(d, 0.0, where=mc)  # zero gain without an observation
            np.copyto(al, 0.0, where=mc)
        for i in range(M):
            np.multiply(pi[i], d, out=k_i)  # eq. (12), k_i = π_i / (1 + ỹᵀπ)
            np.multiply(k_i, al, out=wo[i])
            wo[i] += wi[i]  # eq. (14)
            for j in range(i, M):  # eq. (15) bracket: P − k ỹᵀ P = P − k πᵀ
                out = po[idx[i, j]]
                np.multiply(k_i, pi[j], out=out)
                np.subtract(pin[idx[i, j]], out, out=out)
        np.copyto(tr, po[diag[0]])
        for i in range(1, M):
            tr += po[diag[i]]
        # eq. (15): × λ⁻¹ where an observation arrived and the trace stays within the bound
        if lam != 1.0:
            tr *= inv_lam
            np.less_equal(tr, trace_max, out=tmp, casting="unsafe")
            if any_miss:
                np.copyto(tmp, 0.0, where=mc)
            tmp *= inv_lam - 1.0
            tmp += 1.0
            for row in po:
                row *= tmp
        # safety net: covariance reset to c I (see mvtrack.filters.rls)
        np.copyto(tmp, po[diag[0]])
        for i in range(1, M):
            np.minimum(tmp, po[diag[i]], out=tmp)
        if not (bool(np.all(tmp > 0.0)) and bool(np.all(_finite(tr)))):
            bad = ~_finite(tr)
            for i in range(M):
                bad |= ~(po[diag[i]] > 0.0)
            for i in range(M):
                for j in range(i, M):
                    po[idx[i, j], bad] = c if i == j else 0.0
        np.copyto(to[0], yc)  # the observation shifts into the delay line ...
        np.copyto(to[0], fc if use_fill else yh, where=mc)  # ... or fill / the prediction
        for i in range(1, M):
            np.copyto(to[i], u[i - 1])

    any_miss = bool(miss.any())
    _chunked(kernel, [w, p, taps, y_in, miss, fill_in, w_out, p_out, taps_out, alpha], B, 5 + M)
    return w_out, p_out, taps_out, alpha
