"""Batched linear Kalman filter, eqs. (3)–(7) of paper 1, as pure functions over arrays.

A batch of ``N`` independent filters is a state ``x`` (N, n) and a covariance ``P``
(N, n, n); any number of leading batch dimensions works the same way (the structured filter
runs ``(objects, parts, n)``). The model matrices ``F, Q`` (and ``H, R``) are either shared
by the whole batch (2-D arrays) or given per filter (with the batch's leading dimensions).
Nothing is modified in place; every function returns new arrays.

:func:`predict` and :func:`update` are the standard steps; :func:`gain` and :func:`joseph`
are the two halves of the update for filters that form their own innovation (eq. (13) of
paper 3 in :mod:`mvtrack.filters.structured`).

Covariances stay symmetric positive definite: the update uses the Joseph form
``P = (I − KH) P̄ (I − KH)ᵀ + K R Kᵀ`` (algebraically equal to eq. (5), but PSD by
construction) and every returned covariance is symmetrised, ``(P + Pᵀ)/2``.
"""

from __future__ import annotations

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray

__all__ = ["gain", "innovation", "joseph", "predict", "update", "valid_rows"]


def _as_state(x: FloatArray, P: FloatArray) -> tuple[FloatArray, FloatArray]:
    x = np.asarray(x, dtype=np.float64)
    P = np.asarray(P, dtype=np.float64)
    if x.ndim < 2:
        raise ValueError(f"x must have shape (N, n), got {x.shape}")
    n = x.shape[-1]
    if P.shape != (*x.shape, n):
        want = ", ".join(str(v) for v in (*x.shape, n))
        raise ValueError(f"P must have shape ({want}) to match x, got {P.shape}")
    return x, P


def _as_matrix(
    name: str, a: FloatArray, lead: tuple[int, ...], rows: int, cols: int
) -> FloatArray:
    a = np.asarray(a, dtype=np.float64)
    if a.shape != (rows, cols) and a.shape != (*lead, rows, cols):
        batch = ", ".join(str(v) for v in (*lead, rows, cols))
        raise ValueError(
            f"{name} must have shape ({rows}, {cols}) or ({batch}), got {a.shape}"
        )
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} holds NaN or infinite values")
    return a


def _sym(P: FloatArray) -> FloatArray:
    return 0.5 * (P + np.swapaxes(P, -1, -2))


def _mT(a: FloatArray) -> FloatArray:
    return np.swapaxes(a, -1, -2)


def predict(
    x: FloatArray, P: FloatArray, F: FloatArray, Q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Time update of ``N`` filters, eqs. (6)–(7) of paper 1.

    .. math::
        \\bar x_{k+1} = F \\hat x_k \\quad (6) \\qquad
        \\bar P_{k+1} = F P_k F^T + Q \\quad (7)

    Parameters
    ----------
    x : ndarray (N, n)
        Posterior states x̂_k.
    P : ndarray (N, n, n)
        Posterior covariances P_k.
    F : ndarray (n, n) or (N, n, n)
        Transition matrix, shared or per filter.
    Q : ndarray (n, n) or (N, n, n)
        Process-noise covariance, shared or per filter.

    Returns
    -------
    x_pred : ndarray (N, n)
    P_pred : ndarray (N, n, n)
    """
    x, P = _as_state(x, P)
    lead, n = x.shape[:-1], x.shape[-1]
    F = _as_matrix("F", F, lead, n, n)
    Q = _as_matrix("Q", Q, lead, n, n)
    x_pred = (F @ x[..., None])[..., 0]  # eq. (6)
    P_pred = F @ P @ _mT(F) + Q  # eq. (7)
    return x_pred, _sym(P_pred)


def innovation(
    x: FloatArray, P: FloatArray, H: FloatArray, R: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Predicted measurement and innovation covariance of ``N`` filters.

    .. math::
        \\hat z = H \\bar x, \\qquad S = H \\bar P H^T + R

    (``S`` is the matrix inverted in eq. (3) of paper 1.)

    Parameters
    ----------
    x : ndarray (N, n)
        Predicted states x̄_k.
    P : ndarray (N, n, n)
        Predicted covariances P̄_k.
    H : ndarray (m, n) or (N, m, n)
        Measurement matrix.
    R : ndarray (m, m) or (N, m, m)
        Measurement-noise covariance.

    Returns
    -------
    z_pred : ndarray (N, m)
    S : ndarray (N, m, m)
    """
    x, P = _as_state(x, P)
    H, R = _as_observation(H, R, x.shape[:-1], x.shape[-1])
    z_pred = (H @ x[..., None])[..., 0]
    return z_pred, _innovation_cov(P, H, R)


def _as_observation(
    H: FloatArray, R: FloatArray, lead: tuple[int, ...], n: int
) -> tuple[FloatArray, FloatArray]:
    H = np.asarray(H, dtype=np.float64)
    m = H.shape[-2] if H.ndim >= 2 else -1
    return _as_matrix("H", H, lead, m, n), _as_matrix("R", R, lead, m, m)


def _innovation_cov(P: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    return _sym(H @ P @ _mT(H) + R)  # eq. (3), the bracket


def _gain(P: FloatArray, H: FloatArray, S: FloatArray) -> FloatArray:
    PHt = P @ _mT(H)
    return _mT(np.linalg.solve(S, _mT(PHt)))  # eq. (3): K = P̄Hᵀ S⁻¹ (S symmetric)


def _joseph(P: FloatArray, K: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    IKH = np.eye(P.shape[-1]) - K @ H
    return _sym(IKH @ P @ _mT(IKH) + K @ R @ _mT(K))  # eq. (5), Joseph form


def gain(P: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    """Kalman gain of every filter of a batch, eq. (3) of paper 1.

    .. math::
        K = \\bar P H^T (H \\bar P H^T + R)^{-1} \\quad (3)

    Parameters
    ----------
    P : ndarray (..., n, n)
        Predicted covariances P̄ (any leading batch dimensions).
    H : ndarray (m, n) or (..., m, n)
        Measurement matrix.
    R : ndarray (m, m) or (..., m, m)
        Measurement-noise covariance.

    Returns
    -------
    ndarray (..., n, m)
    """
    P = np.asarray(P, dtype=np.float64)
    if P.ndim < 3 or P.shape[-1] != P.shape[-2]:
        raise ValueError(f"P must have shape (N, n, n), got {P.shape}")
    H, R = _as_observation(H, R, P.shape[:-2], P.shape[-1])
    return _gain(P, H, _innovation_cov(P, H, R))


def joseph(P: FloatArray, K: FloatArray, H: FloatArray, R: FloatArray) -> FloatArray:
    """Posterior covariance for the gain ``K``, eq. (5) of paper 1 in Joseph form.

    .. math::
        P = (I - K H) \\bar P (I - K H)^T + K R K^T \\quad (5)

    Parameters
    ----------
    P : ndarray (..., n, n)
        Predicted covariances P̄.
    K : ndarray (..., n, m)
        Gains (:func:`gain`).
    H : ndarray (m, n) or (..., m, n)
    R : ndarray (m, m) or (..., m, m)

    Returns
    -------
    ndarray (..., n, n)
        Symmetric; positive definite whatever the gain.
    """
    P = np.asarray(P, dtype=np.float64)
    if P.ndim < 3 or P.shape[-1] != P.shape[-2]:
        raise ValueError(f"P must have shape (N, n, n), got {P.shape}")
    H, R = _as_observation(H, R, P.shape[:-2], P.shape[-1])
    return _joseph(P, np.asarray(K, dtype=np.float64), H, R)


def valid_rows(z: FloatArray, mask: BoolArray | None) -> BoolArray:
    """Rows of ``z`` (N, m) that carry a measurement: ``mask`` true and no NaN/inf in the row."""
    ok = np.all(np.isfinite(z), axis=-1)
    if mask is not None:
        ok &= mask
    return ok


def update(
    x: FloatArray,
    P: FloatArray,
    z: FloatArray,
    H: FloatArray,
    R: FloatArray,
    mask: BoolArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Measurement update of ``N`` filters, eqs. (3)–(5) of paper 1.

    .. math::
        K_k = \\bar P_k H^T (H \\bar P_k H^T + R)^{-1} \\quad (3) \\\\
        \\hat x_k = \\bar x_k + K_k (z_k - H \\bar x_k) \\quad (4) \\\\
        P_k = (I - K_k H) \\bar P_k (I - K_k H)^T + K_k R K_k^T \\quad (5)

    Eq. (5) is used in the Joseph form, which equals the printed ``(I − K H) P̄`` for the
    optimal gain and keeps ``P`` symmetric positive definite in floating point.

    Parameters
    ----------
    x : ndarray (N, n)
        Predicted states x̄_k.
    P : ndarray (N, n, n)
        Predicted covariances P̄_k.
    z : ndarray (N, m)
        Measurements; a row holding NaN (or ±inf) is a missing measurement.
    H : ndarray (m, n) or (N, m, n)
    R : ndarray (m, m) or (N, m, m)
    mask : ndarray (N,) of bool, optional
        False for filters that got no measurement this frame.

    Returns
    -------
    x_post : ndarray (N, n)
    P_post : ndarray (N, n, n)
        Rows without a measurement are returned unchanged (the prediction is kept); a
        missing measurement never reaches the arithmetic, so it cannot poison the state.
    """
    x, P = _as_state(x, P)
    lead = x.shape[:-1]
    H, R = _as_observation(H, R, lead, x.shape[-1])
    m = H.shape[-2]
    z = np.asarray(z, dtype=np.float64)
    if z.shape != (*lead, m):
        want = ", ".join(str(v) for v in (*lead, m))
        raise ValueError(f"z must have shape ({want}), got {z.shape}")
    if mask is not None:
        mask = np.asarray(mask)
        if mask.shape != lead or mask.dtype != np.bool_:
            want = ", ".join(str(v) for v in lead)
            raise ValueError(f"mask must be a boolean array of shape ({want},), got {mask.shape}")
    ok = valid_rows(z, mask)
    z_pred = (H @ x[..., None])[..., 0]
    S = _innovation_cov(P, H, R)
    # missing rows get a zero innovation, so NaNs never enter the arithmetic
    nu = np.where(ok[..., None], z, z_pred) - z_pred
    K = _gain(P, H, S)  # eq. (3)
    x_post = x + (K @ nu[..., None])[..., 0]  # eq. (4)
    P_post = _joseph(P, K, H, R)  # eq. (5), Joseph form
    x_post = np.where(ok[..., None], x_post, x)
    P_post = np.where(ok[..., None, None], P_post, P)
    return x_post, P_post
