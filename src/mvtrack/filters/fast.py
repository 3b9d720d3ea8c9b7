"""Fast kernels for the per-axis filters the tracker runs every frame.

Same mathematics as :mod:`mvtrack.filters.kalman` and :mod:`mvtrack.filters.rls`, for the
special cases the predictors use: a 1-D model whose ``H = [1, 0, …]`` selects the position
(so the KF update is a rank-1 correction and ``S`` a scalar) and the RLS step. They skip the
input validation of the generic functions (the predictors validate), and are tested equal to
the generic functions in ``tests/test_fast.py``.
"""

from __future__ import annotations

import numpy as np

from mvtrack.filters import kalman, rls
from mvtrack.filters.base import BoolArray, FloatArray

__all__ = ["axis_predict", "axis_update", "rls_update"]


def axis_predict(
    x: FloatArray, P: FloatArray, F: FloatArray, Q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Eqs. (6)–(7) of paper 1 for ``B`` per-axis filters, x (B, n), P (B, n, n)."""
    return kalman.predict(x, P, F, Q)


def axis_update(
    x: FloatArray, P: FloatArray, z: FloatArray, r: float, ok: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Eqs. (3)–(5) of paper 1 with ``H = [1, 0, …]``, ``R = r``; z (B,), ok (B,)."""
    n = x.shape[1]
    H = np.eye(n)[:1]
    return kalman.update(x, P, z[:, None], H, np.array([[r]]), ok)


def rls_update(
    w: FloatArray,
    P: FloatArray,
    taps: FloatArray,
    y: FloatArray,
    lam: float,
    ok: BoolArray,
    trace_max: float,
) -> tuple[rls.RLSState, FloatArray]:
    """Eqs. (12)–(15) of paper 1 for ``B`` predictors (see :func:`mvtrack.filters.rls.update`)."""
    return rls.update(rls.RLSState(w, P, taps), y, lam, ok, trace_max)
