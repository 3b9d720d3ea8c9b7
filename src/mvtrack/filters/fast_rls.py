"""Fast kernel of the per-axis RLS predictor, eqs. (10)–(15) of paper 1.

Same mathematics as :mod:`mvtrack.filters.rls`, in the component-first layout of
:mod:`mvtrack.filters.layout` (see :mod:`mvtrack.filters.fast` for the Kalman kernels).
"""

from __future__ import annotations

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray
from mvtrack.filters.layout import chunked, finite, packed_index

__all__ = ["rls_step"]


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
    miss = ~(ok & finite(y_in))
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
        if not (bool(np.all(tmp > 0.0)) and bool(np.all(finite(tr)))):
            bad = ~finite(tr)
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
    chunked(kernel, [w, p, taps, y_in, miss, fill_in, w_out, p_out, taps_out, alpha], B, 5 + M)
    return w_out, p_out, taps_out, alpha
