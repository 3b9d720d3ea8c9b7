"""The batched Kalman filter equals filterpy's KalmanFilter, keeps P SPD and honours masks."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.filters import kalman
from mvtrack.filters.models import constant_acceleration


def _random_spd(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


def _random_model(rng: np.random.Generator, n: int, m: int):
    F = np.eye(n) + 0.3 * rng.normal(size=(n, n))
    H = rng.normal(size=(m, n))
    return F, H, _random_spd(rng, n, 0.1), _random_spd(rng, m)


def _filterpy_run(x0, P0, F, H, Q, R, zs):
    kf = KalmanFilter(dim_x=len(x0), dim_z=H.shape[0])
    kf.x, kf.P, kf.F, kf.H, kf.Q, kf.R = x0.copy(), P0.copy(), F, H, Q, R
    out = []
    for z in zs:
        kf.predict()
        out.append((kf.x.copy(), kf.P.copy()))
        if z is None:
            kf.update(None)
        else:
            kf.update(z)
        out.append((kf.x.copy(), kf.P.copy()))
    return out


@pytest.mark.parametrize("n,m", [(1, 1), (2, 1), (3, 1), (4, 2), (6, 2), (5, 3)])
def test_batched_filter_matches_filterpy_with_shared_model(n: int, m: int) -> None:
    rng = np.random.default_rng(10 * n + m)
    F, H, Q, R = _random_model(rng, n, m)
    N, T = 5, 12
    x = rng.normal(size=(N, n))
    P = np.stack([_random_spd(rng, n) for _ in range(N)])
    zs = rng.normal(size=(T, N, m)) * 3
    masks = rng.random((T, N)) > 0.25
    refs = [
        _filterpy_run(x[i], P[i], F, H, Q, R, [zs[t, i] if masks[t, i] else None for t in range(T)])
        for i in range(N)
    ]
    for t in range(T):
        x, P = kalman.predict(x, P, F, Q)
        for i in range(N):
            np.testing.assert_allclose(x[i], refs[i][2 * t][0], rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(P[i], refs[i][2 * t][1], rtol=1e-9, atol=1e-12)
        x, P = kalman.update(x, P, zs[t], H, R, masks[t])
        for i in range(N):
            np.testing.assert_allclose(x[i], refs[i][2 * t + 1][0], rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(P[i], refs[i][2 * t + 1][1], rtol=1e-9, atol=1e-12)


def test_per_target_models_match_filterpy_one_by_one() -> None:
    rng = np.random.default_rng(7)
    n, m, N, T = 3, 2, 4, 10
    models = [_random_model(rng, n, m) for _ in range(N)]
    F = np.stack([mo[0] for mo in models])
    H = np.stack([mo[1] for mo in models])
    Q = np.stack([mo[2] for mo in models])
    R = np.stack([mo[3] for mo in models])
    x0 = rng.normal(size=(N, n))
    P0 = np.stack([_random_spd(rng, n) for _ in range(N)])
    zs = rng.normal(size=(T, N, m))
    x, P = x0, P0
    for t in range(T):
        x, P = kalman.predict(x, P, F, Q)
        x, P = kalman.update(x, P, zs[t], H, R)
    for i in range(N):
        ref = _filterpy_run(x0[i], P0[i], F[i], H[i], Q[i], R[i], list(zs[:, i]))[-1]
        np.testing.assert_allclose(x[i], ref[0], rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(P[i], ref[1], rtol=1e-9, atol=1e-12)


def test_innovation_is_Hx_and_HPHt_plus_R() -> None:
    x = np.array([[1.0, 2.0, 3.0]])
    P = np.diag([4.0, 5.0, 6.0])[None]
    H = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])
    R = np.array([[1.0, 0.5], [0.5, 2.0]])
    z, S = kalman.innovation(x, P, H, R)
    np.testing.assert_allclose(z, [[1.0, 5.0]])
    np.testing.assert_allclose(S, [[[5.0, 0.5], [0.5, 13.0]]])


def test_scalar_update_by_hand() -> None:
    # P̄ = 3, R = 1: K = 3/4, x = 2 + 3/4 (6 - 2) = 5, P = (1 - 3/4) 3 = 3/4
    x, P = kalman.update(np.array([[2.0]]), np.array([[[3.0]]]), np.array([[6.0]]),
                         np.array([[1.0]]), np.array([[1.0]]))
    assert x[0, 0] == pytest.approx(5.0, rel=1e-15)
    assert P[0, 0, 0] == pytest.approx(0.75, rel=1e-15)


def test_ca_filter_predicts_noise_free_quadratic_motion_exactly() -> None:
    model = constant_acceleration(dt=1.0, q=1e-6, r=1e-6)
    k = np.arange(60, dtype=float)
    p = 3.0 + 2.0 * k - 0.25 * k**2
    x = np.zeros((1, 3))
    P = np.eye(3)[None] * 1e4
    errs = []
    for t in range(60):
        x, P = kalman.predict(x, P, model.F, model.Q)
        errs.append(x[0, 0] - p[t])
        x, P = kalman.update(x, P, p[t : t + 1, None], model.H, model.R)
    assert abs(errs[0]) > 1.0
    assert max(abs(e) for e in errs[20:]) < 1e-3
    np.testing.assert_allclose(x[0], [p[-1], 2.0 - 0.5 * 59, -0.5], rtol=1e-4, atol=1e-4)


def test_nan_measurement_keeps_prediction_and_does_not_poison() -> None:
    model = constant_acceleration()
    x = np.array([[1.0, 2.0, 0.0], [5.0, -1.0, 0.1]])
    P = np.stack([np.eye(3)] * 2)
    z = np.array([[np.nan], [4.0]])
    x2, P2 = kalman.update(x, P, z, model.H, model.R)
    np.testing.assert_array_equal(x2[0], x[0])
    np.testing.assert_array_equal(P2[0], P[0])
    assert np.all(np.isfinite(x2)) and np.all(np.isfinite(P2))
    x3, _ = kalman.update(x, P, np.array([[7.0], [4.0]]), model.H, model.R, np.array([True, True]))
    np.testing.assert_array_equal(x2[1], x3[1])
    x4, _ = kalman.update(x, P, np.array([[np.inf], [4.0]]), model.H, model.R)
    np.testing.assert_array_equal(x4[0], x[0])


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: kalman.predict(np.zeros((2, 3)), np.zeros((2, 3, 2)), np.eye(3), np.eye(3)), "P"),
        (lambda: kalman.predict(np.zeros(3), np.zeros((3, 3)), np.eye(3), np.eye(3)), "x"),
        (lambda: kalman.predict(np.zeros((2, 3)), np.zeros((2, 3, 3)), np.eye(2), np.eye(3)), "F"),
        (lambda: kalman.predict(np.zeros((2, 3)), np.zeros((2, 3, 3)), np.eye(3),
                                np.full((3, 3), np.nan)), "Q"),
        (lambda: kalman.update(np.zeros((2, 3)), np.zeros((2, 3, 3)), np.zeros((2, 2)),
                               np.eye(3)[:1], np.eye(1)), "z"),
        (lambda: kalman.update(np.zeros((2, 3)), np.zeros((2, 3, 3)), np.zeros((2, 1)),
                               np.eye(3)[:1], np.eye(2)), "R"),
        (lambda: kalman.update(np.zeros((2, 3)), np.zeros((2, 3, 3)), np.zeros((2, 1)),
                               np.eye(3)[:1], np.eye(1), np.ones(3, bool)), "mask"),
    ],
)
def test_bad_shapes_raise_value_error_naming_the_parameter(call, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(1, 5),
    m=st.integers(1, 3),
    N=st.integers(0, 6),
    seed=st.integers(0, 2**31 - 1),
    steps=st.integers(1, 30),
)
def test_property_shapes_symmetry_pd_and_mask(n, m, N, seed, steps) -> None:
    rng = np.random.default_rng(seed)
    F, H, Q, R = _random_model(rng, n, m)
    F = F / max(1.0, np.abs(np.linalg.eigvals(F)).max())  # keep the run bounded
    x = rng.normal(size=(N, n))
    P = np.stack([_random_spd(rng, n) for _ in range(N)]) if N else np.zeros((0, n, n))
    for _ in range(steps):
        x, P = kalman.predict(x, P, F, Q)
        assert x.shape == (N, n) and P.shape == (N, n, n)
        z = rng.normal(size=(N, m))
        z[rng.random(N) < 0.2] = np.nan
        mask = rng.random(N) > 0.2
        xu, Pu = kalman.update(x, P, z, H, R, mask)
        keep = ~(mask & np.isfinite(z).all(axis=1))
        np.testing.assert_array_equal(xu[keep], x[keep])
        np.testing.assert_array_equal(Pu[keep], P[keep])
        x, P = xu, Pu
        assert np.all(np.isfinite(x))
        np.testing.assert_array_equal(P, np.swapaxes(P, 1, 2))
        if N:
            assert np.linalg.eigvalsh(P).min() > 0


def test_leading_batch_dimensions_equal_the_flat_batch() -> None:
    """(N, K, n) states give exactly the rows of the flat (N·K, n) batch; gain and Joseph
    form are the halves of update."""
    rng = np.random.default_rng(3)
    model = constant_acceleration(dt=1.0, q=0.05, r=4.0)
    N, K, n = 4, 3, model.F.shape[0]
    x = rng.normal(size=(N, K, n))
    A = rng.normal(size=(N, K, n, n))
    P = A @ np.swapaxes(A, -1, -2) + np.eye(n)
    xp, Pp = kalman.predict(x, P, model.F, model.Q)
    fx, fP = kalman.predict(x.reshape(-1, n), P.reshape(-1, n, n), model.F, model.Q)
    assert np.array_equal(xp.reshape(-1, n), fx) and np.array_equal(Pp.reshape(-1, n, n), fP)
    z = rng.normal(size=(N, K, 1))
    mask = rng.random((N, K)) > 0.3
    xu, Pu = kalman.update(xp, Pp, z, model.H, model.R, mask)
    gx, gP = kalman.update(fx, fP, z.reshape(-1, 1), model.H, model.R, mask.ravel())
    assert np.array_equal(xu.reshape(-1, n), gx) and np.array_equal(Pu.reshape(-1, n, n), gP)
    K_gain = kalman.gain(Pp, model.H, model.R)
    assert np.array_equal(
        np.where(mask[..., None, None], kalman.joseph(Pp, K_gain, model.H, model.R), Pp), Pu
    )
    with pytest.raises(ValueError, match="mask"):
        kalman.update(xp, Pp, z, model.H, model.R, mask.ravel())
