"""The RLS predictor (eqs. 12–15 of paper 1) against closed-form least squares and standard RLS."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.filters import rls


def _regressors(y: np.ndarray, M: int) -> np.ndarray:
    """ỹ_n = [y_{n−1} … y_{n−M}] for n = 1…T (y_0 is the first sample; earlier samples are 0)."""
    padded = np.concatenate([np.zeros(M), y])
    return np.stack([padded[M + n - 1 - np.arange(M)] for n in range(len(y))])


def _run(y: np.ndarray, M: int, lam: float, c: float, trace_max: float | None = None):
    """Feed the columns of y (T, B) one by one; return weights after every step (T, B, M)."""
    T, B = y.shape
    s = rls.init(B, M, c)
    ws, alphas = [], []
    for t in range(T):
        s, a = rls.update(s, y[t], lam, trace_max=trace_max, c=c)
        ws.append(s.w)
        alphas.append(a)
    return s, np.stack(ws), np.stack(alphas)


def _closed_form(y: np.ndarray, M: int, lam: float, c: float) -> np.ndarray:
    """ŵ_n = (λ^{n−1} c⁻¹ I + Σ λ^{n−i} ỹ_i ỹ_iᵀ)⁻¹ Σ λ^{n−i} ỹ_i y_i (module docstring, E1.1)."""
    U = _regressors(y, M)
    n = len(y)
    wts = lam ** (n - 1 - np.arange(n))
    A = lam ** (n - 1) / c * np.eye(M) + (U * wts[:, None]).T @ U
    b = (U * wts[:, None]).T @ y
    return np.linalg.solve(A, b)


@pytest.mark.parametrize("M", [1, 2, 3, 5])
def test_lambda_one_equals_ridge_least_squares(M: int) -> None:
    rng = np.random.default_rng(M)
    y = np.cumsum(rng.normal(size=80))
    _, ws, _ = _run(y[:, None], M, 1.0, 100.0)
    for n in (5, 20, 80):
        U = _regressors(y[:n], M)
        w_ref = np.linalg.solve(U.T @ U + np.eye(M) / 100.0, U.T @ y[:n])
        np.testing.assert_allclose(ws[n - 1, 0], w_ref, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("lam", [0.9, 0.95, 0.98])
@pytest.mark.parametrize("M", [1, 3, 4])
def test_forgetting_equals_exponentially_weighted_closed_form(lam: float, M: int) -> None:
    rng = np.random.default_rng(int(lam * 100) + M)
    y = np.cumsum(rng.normal(size=120)) + rng.normal(size=120)
    _, ws, _ = _run(y[:, None], M, lam, 100.0, trace_max=np.inf)
    for n in (3, 30, 120):
        np.testing.assert_allclose(ws[n - 1, 0], _closed_form(y[:n], M, lam, 100.0),
                                   rtol=1e-8, atol=1e-10)


def test_printed_P_is_inverse_of_weighted_correlation_over_lambda() -> None:
    rng = np.random.default_rng(3)
    y = rng.normal(size=40)
    lam, c, M = 0.95, 50.0, 3
    s, _, _ = _run(y[:, None], M, lam, c, trace_max=np.inf)
    U = _regressors(y, M)
    n = len(y)
    P_inv = lam**n / c * np.eye(M) + (U * lam ** (n - np.arange(n))[:, None]).T @ U
    np.testing.assert_allclose(s.P[0], np.linalg.inv(P_inv), rtol=1e-8)


def _standard_rls(y: np.ndarray, M: int, lam: float, P0: np.ndarray) -> np.ndarray:
    """Textbook exponentially weighted RLS (Haykin): k = λ⁻¹Pu / (1 + λ⁻¹uᵀPu)."""
    w = np.zeros(M)
    P = P0.copy()
    u = np.zeros(M)
    out = []
    for yn in y:
        pi = P @ u
        k = pi / (lam + u @ pi)
        w = w + k * (yn - w @ u)
        P = (P - np.outer(k, pi)) / lam
        u = np.concatenate([[yn], u[:-1]])
        out.append(w.copy())
    return np.array(out)


@pytest.mark.parametrize("lam", [0.95, 0.98])
def test_printed_form_equals_standard_rls_with_P0_scaled_by_lambda(lam: float) -> None:
    # X10 last bullet / E1.1
    rng = np.random.default_rng(11)
    y = np.cumsum(rng.normal(size=200))
    c, M = 100.0, 3
    _, ws, _ = _run(y[:, None], M, lam, c, trace_max=np.inf)
    w_std = _standard_rls(y, M, lam, lam * c * np.eye(M))
    np.testing.assert_allclose(ws[:, 0], w_std, rtol=1e-9, atol=1e-9)
    # without rescaling P0 they differ (the printed (12) is not the textbook gain)
    w_unscaled = _standard_rls(y, M, lam, c * np.eye(M))
    assert np.abs(ws[:, 0] - w_unscaled).max() > 1e-6


def test_alpha_is_a_priori_error_and_prediction_uses_newest_samples() -> None:
    s = rls.init(1, 2, 10.0)
    s, a1 = rls.update(s, np.array([2.0]), 1.0)
    assert a1[0] == 2.0  # ŵ₀ = 0
    np.testing.assert_array_equal(s.taps, [[2.0, 0.0]])
    # ỹ₂ = [2, 0]: k = P ỹ / (1 + ỹᵀPỹ) = [20, 0] / 41, ŵ₂ = 3 · 20/41 on the first tap
    s, a2 = rls.update(s, np.array([3.0]), 1.0)
    assert a2[0] == 3.0
    np.testing.assert_allclose(s.w, [[60.0 / 41.0, 0.0]], rtol=1e-14)
    # E1.5: the next prediction is ŵ₂ᵀ[y₂, y₁] = 60/41 · 3
    np.testing.assert_allclose(rls.predict(s), [180.0 / 41.0], rtol=1e-14)


def test_noise_free_quadratic_motion_learns_3_minus3_1() -> None:
    # y_n = 3 y_{n−1} − 3 y_{n−2} + y_{n−3} for every quadratic; the weakest-excited direction
    # is [1, −2, 1] (the constant second difference), so convergence there takes a few hundred
    # samples (λ = 0.9 forgets the zero-history start quickly).
    k = np.arange(400, dtype=float)
    y = 2.0 + 1.5 * k - 0.25 * k**2
    _, ws, alphas = _run(y[:, None], 3, 0.9, 100.0)
    np.testing.assert_allclose(ws[-1, 0], [3.0, -3.0, 1.0], atol=1e-4)
    assert np.abs(ws[99, 0] - [3.0, -3.0, 1.0]).max() > 1e-4  # it did have to learn
    assert np.abs(alphas[-50:, 0]).max() < 1e-6


def test_batched_equals_one_by_one() -> None:
    rng = np.random.default_rng(5)
    y = np.cumsum(rng.normal(size=(60, 7)), axis=0)
    mask = rng.random((60, 7)) > 0.2
    s = rls.init(7, 3, 100.0)
    for t in range(60):
        s, _ = rls.update(s, y[t], 0.95, mask[t])
    for b in range(7):
        sb = rls.init(1, 3, 100.0)
        for t in range(60):
            sb, _ = rls.update(sb, y[t, b : b + 1], 0.95, mask[t, b : b + 1])
        np.testing.assert_allclose(s.w[b], sb.w[0], rtol=1e-13)
        np.testing.assert_allclose(s.P[b], sb.P[0], rtol=1e-13)


def test_missing_observation_keeps_weights_and_feeds_prediction() -> None:
    rng = np.random.default_rng(2)
    s = rls.init(2, 3, 100.0)
    for yt in np.cumsum(rng.normal(size=(20, 2)), axis=0):
        s, _ = rls.update(s, yt, 0.98)
    pred = rls.predict(s)
    s2, a = rls.update(s, np.array([np.nan, 1.0]), 0.98, np.array([True, False]))
    assert np.isnan(a).all()
    np.testing.assert_array_equal(s2.w, s.w)
    np.testing.assert_array_equal(s2.P, s.P)
    np.testing.assert_array_equal(s2.taps[:, 0], pred)
    np.testing.assert_array_equal(s2.taps[:, 1:], s.taps[:, :-1])


def test_guard_bounds_trace_under_constant_input() -> None:
    s = rls.init(3, 3, 100.0)
    y = np.array([0.0, 120.0, 640.0])
    for _ in range(3000):
        s, _ = rls.update(s, y, 0.9)
    tr = np.trace(s.P, axis1=1, axis2=2)
    assert np.all(tr <= 10 * 100.0 * 3 * (1 + 1e-12))
    np.testing.assert_allclose(rls.predict(s), y, rtol=1e-9, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(s.P) > 0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"M": 0}, "M"),
        ({"M": 2.5}, "M"),
        ({"c": 0.0}, "c"),
        ({"c": np.nan}, "c"),
        ({"lam": 0.0}, "lam"),
        ({"lam": 1.01}, "lam"),
        ({"lam": np.nan}, "lam"),
    ],
)
def test_bad_parameters_raise_value_error(kwargs, match) -> None:
    params = {"M": 3, "lam": 0.98, "c": 100.0} | kwargs
    with pytest.raises(ValueError, match=match):
        rls.check_params(params["M"], params["lam"], params["c"])


def test_bad_observation_shape_raises() -> None:
    with pytest.raises(ValueError, match="y"):
        rls.update(rls.init(2), np.zeros(3))
    with pytest.raises(ValueError, match="mask"):
        rls.update(rls.init(2), np.zeros(2), mask=np.ones(3, bool))


@settings(max_examples=30, deadline=None)
@given(B=st.integers(0, 5), M=st.integers(1, 4), seed=st.integers(0, 2**31 - 1),
       lam=st.floats(0.8, 1.0))
def test_property_shapes_symmetry_pd(B, M, seed, lam) -> None:
    rng = np.random.default_rng(seed)
    s = rls.init(B, M, 100.0)
    for _ in range(25):
        y = rng.normal(size=B) * 10
        y[rng.random(B) < 0.2] = np.nan
        s, a = rls.update(s, y, lam)
        assert s.w.shape == (B, M) and s.P.shape == (B, M, M) and s.taps.shape == (B, M)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(y))
        assert np.all(np.isfinite(s.w)) and np.all(np.isfinite(s.taps))
        np.testing.assert_array_equal(s.P, np.swapaxes(s.P, 1, 2))
        if B:
            assert np.linalg.eigvalsh(s.P).min() > 0
