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
    "pack",
    "packed_index",
    "rls_step",
    "unpack",
]

#: filters per chunk (keeps about 20 temporaries of CHUNK doubles in the L2/L3 cache)
CHUNK = 32768


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


def _chunked(fn: Callable[..., None], arrays: list[FloatArray], B: int) -> None:
    """Call ``fn`` on column slices ``[s:s+CHUNK]`` of every array (all with last dim B)."""
    if B <= CHUNK:
        fn(*arrays)
        return
    for s in range(0, B, CHUNK):
        fn(*[a[..., s : s + CHUNK] for a in arrays])


def _lincomb(terms: list[tuple[float, FloatArray]], out: FloatArray, tmp: FloatArray) -> None:
    """``out[:] = Σ c·a`` over ``terms`` (zero coefficients already dropped; none empty)."""
    c0, a0 = terms[0]
    if c0 == 1.0:
        np.copyto(out, a0)
    else:
        np.multiply(a0, c0, out=out)
    for c, a in terms[1:]:
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

    def kernel(xc: FloatArray, pc: FloatArray, xo: FloatArray, po: FloatArray) -> None:
        tmp = np.empty(xc.shape[1])
        for i in range(n):  # eq. (6)
            _lincomb([(F[i, k], xc[k]) for k in range(n) if F[i, k] != 0.0], xo[i], tmp)
        # A = F P, only the entries A_il that some upper-triangle P'_ij (j ≥ i) needs
        A: dict[tuple[int, int], FloatArray] = {}
        for i in range(n):
            need = {ll for j in range(i, n) for ll in range(n) if F[j, ll] != 0.0}
            for ll in sorted(need):
                terms = [(F[i, k], pc[idx[k, ll]]) for k in range(n) if F[i, k] != 0.0]
                if len(terms) == 1 and terms[0][0] == 1.0:
                    A[i, ll] = terms[0][1]
                else:
                    A[i, ll] = np.empty(xc.shape[1])
                    _lincomb(terms, A[i, ll], tmp)
        for i in range(n):  # eq. (7): P' = A Fᵀ + Q, upper triangle
            for j in range(i, n):
                out = po[idx[i, j]]
                _lincomb([(F[j, ll], A[i, ll]) for ll in range(n) if F[j, ll] != 0.0], out, tmp)
                if Q[i, j] != 0.0:
                    out += Q[i, j]

    _chunked(kernel, [x, p, x_out, p_out], B)
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
    x_out = x.copy()
    p_out = p.copy()
    okf = ok.astype(np.float64)
    z_safe = np.where(ok, z, x[0])  # a missing measurement never enters the arithmetic

    def kernel(xo: FloatArray, po: FloatArray, zc: FloatArray, okc: FloatArray) -> None:
        g = po[idx[0, 0]] + r  # S
        np.divide(okc, g, out=g)  # ok / S: zero gain where there is no measurement
        nu = zc - xo[0]  # innovation
        nu *= g
        k = [po[idx[0, i]] * g for i in range(n)]  # eq. (3), K_i = P_0i / S
        tmp = np.empty_like(nu)
        for i in range(n):  # eq. (4)
            np.multiply(po[idx[0, i]], nu, out=tmp)
            xo[i] += tmp
        for i in range(n - 1, -1, -1):  # eq. (5): P_ij −= K_i P_0j (P_0j updated last)
            for j in range(n - 1, i - 1, -1):
                np.multiply(k[i], po[idx[0, j]], out=tmp)
                po[idx[i, j]] -= tmp

    _chunked(kernel, [x_out, p_out, z_safe, okf], B)
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
    w_out = w.copy()
    p_out = p.copy()
    taps_out = np.empty_like(taps)
    alpha = np.empty(B)
    y_in = np.asarray(y, dtype=np.float64)
    ok = ok & np.isfinite(y_in)
    okf = ok.astype(np.float64)
    inv_lam = 1.0 / lam
    fill_in = np.full(B, np.nan) if fill is None else np.asarray(fill, dtype=np.float64)
    own = np.full(B, fill is None)

    def kernel(
        wo: FloatArray, po: FloatArray, u: FloatArray, to: FloatArray, yc: FloatArray,
        okc: FloatArray, al: FloatArray, okb: BoolArray, fc: FloatArray, ownc: BoolArray
    ) -> None:
        tmp = np.empty(u.shape[1])
        pi = []
        for i in range(M):  # π = P_{n−1} ỹ_n
            acc = po[idx[i, 0]] * u[0]
            for j in range(1, M):
                np.multiply(po[idx[i, j]], u[j], out=tmp)
                acc += tmp
            pi.append(acc)
        d = u[0] * pi[0]  # 1 + ỹᵀ π
        yh = wo[0] * u[0]  # ŵ_{n−1}ᵀ ỹ_n
        for i in range(1, M):
            np.multiply(u[i], pi[i], out=tmp)
            d += tmp
            np.multiply(wo[i], u[i], out=tmp)
            yh += tmp
        d += 1.0
        np.divide(okc, d, out=d)  # g = ok / (1 + ỹᵀπ): zero gain without observation
        np.copyto(to[0], yh)
        np.copyto(to[0], yc, where=okb)  # the observation, or the prediction if missing
        np.subtract(to[0], yh, out=al)  # eq. (13), α = y − ŵᵀỹ (0 where missing)
        np.copyto(to[0], fc, where=~(okb | ownc))
        tr = np.zeros_like(d)
        for i in range(M):
            np.multiply(pi[i], d, out=tmp)  # eq. (12), k_i = π_i / (1 + ỹᵀπ)
            k_i = tmp.copy()
            np.multiply(k_i, al, out=tmp)
            wo[i] += tmp  # eq. (14)
            for j in range(i, M):
                np.multiply(k_i, pi[j], out=tmp)
                po[idx[i, j]] -= tmp  # eq. (15) bracket: P − k ỹᵀ P = P − k πᵀ
            tr += po[idx[i, i]]
        # eq. (15): × λ⁻¹ where a measurement arrived and the trace stays within the bound
        scale = np.where((tr * inv_lam <= trace_max) & okb, inv_lam, 1.0)
        for row in po:
            row *= scale
        bad = ~np.isfinite(tr)
        for i in range(M):
            bad |= po[idx[i, i]] <= 0.0
        if bad.any():  # safety net: covariance reset to c I (see mvtrack.filters.rls)
            for i in range(M):
                for j in range(i, M):
                    po[idx[i, j], bad] = c if i == j else 0.0
        for i in range(1, M):
            np.copyto(to[i], u[i - 1])

    _chunked(kernel, [w_out, p_out, taps, taps_out, y_in, okf, alpha, ok, fill_in, own], B)
    return w_out, p_out, taps_out, alpha
