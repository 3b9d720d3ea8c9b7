"""The fast per-axis kernels equal the generic batched filters and the scalar reference code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mvtrack.filters import fast, kalman, rls, scalar
from mvtrack.filters.models import constant_acceleration, constant_velocity


@pytest.fixture(params=[None, 7], ids=["one-chunk", "chunks-of-7"])
def chunk(request, monkeypatch):
    if request.param is not None:
        monkeypatch.setattr(fast, "CHUNK", request.param)
    return request.param


def _spd(rng, B, n):
    A = rng.normal(size=(B, n, n))
    return A @ np.swapaxes(A, 1, 2) + n * np.eye(n)


@pytest.mark.parametrize("model", [constant_acceleration(1.0, 0.3, 2.0),
                                   constant_velocity(0.5, 0.2, 1.5),
                                   constant_acceleration(1 / 30, 0.5, 5.0)])
def test_axis_kernels_equal_generic_kalman(model, chunk) -> None:
    rng = np.random.default_rng(1)
    B, n = 23, model.n
    x = rng.normal(size=(B, n))
    P = _spd(rng, B, n)
    xc, pc = x.T.copy(), fast.pack(P).T.copy()
    for _ in range(15):
        x, P = kalman.predict(x, P, model.F, model.Q)
        xc, pc = fast.kf_axis_predict(xc, pc, model.F, model.Q)
        np.testing.assert_allclose(xc.T, x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(fast.unpack(pc.T, n), P, rtol=1e-10, atol=1e-12)
        z = rng.normal(size=B) * 3
        ok = rng.random(B) > 0.3
        z[~ok & (rng.random(B) > 0.5)] = np.nan
        x, P = kalman.update(x, P, z[:, None], model.H, model.R, ok)
        xc2, pc2 = fast.kf_axis_update(xc, pc, z, float(model.R[0, 0]), ok)
        np.testing.assert_array_equal(xc2[:, ~ok], xc[:, ~ok])  # untouched
        np.testing.assert_array_equal(pc2[:, ~ok], pc[:, ~ok])
        xc, pc = xc2, pc2
        np.testing.assert_allclose(xc.T, x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(fast.unpack(pc.T, n), P, rtol=1e-10, atol=1e-12)


def test_axis_kernels_do_not_modify_their_input() -> None:
    model = constant_acceleration()
    x = np.ones((3, 4))
    p = fast.pack(np.broadcast_to(np.eye(3), (4, 3, 3))).T.copy()
    x0, p0 = x.copy(), p.copy()
    fast.kf_axis_predict(x, p, model.F, model.Q)
    fast.kf_axis_update(x, p, np.zeros(4), 1.0, np.ones(4, bool))
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(p, p0)


@pytest.mark.parametrize("M", [1, 3, 4])
@pytest.mark.parametrize("lam", [1.0, 0.9])
def test_rls_step_equals_generic_rls(M, lam, chunk) -> None:
    rng = np.random.default_rng(M)
    B = 19
    s = rls.init(B, M, 100.0)
    w, p, u = s.w.T.copy(), fast.pack(s.P).T.copy(), s.taps.T.copy()
    # stretches of constant input make the guard act on some rows
    y_all = np.cumsum(rng.normal(size=(120, B)), axis=0)
    y_all[40:, :5] = y_all[40, :5]
    for t in range(120):
        y = y_all[t].copy()
        ok = rng.random(B) > 0.2
        y[~ok & (rng.random(B) > 0.5)] = np.nan
        s, a = rls.update(s, y, lam, ok, trace_max=400.0)
        w, p, u, a2 = fast.rls_step(w, p, u, y, lam, ok, 400.0, 100.0)
        okf = ok & np.isfinite(y)
        np.testing.assert_allclose(w.T, s.w, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(fast.unpack(p.T, M), s.P, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(u.T, s.taps, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(a2[okf], a[okf], rtol=1e-8, atol=1e-10)
        assert np.all(a2[~okf] == 0.0)
    if lam < 1 and M > 1:
        assert np.any(np.trace(s.P, axis1=1, axis2=2) > 350.0)  # the guard was exercised


def test_rls_step_fill_enters_delay_line_of_missing_rows() -> None:
    s = rls.init(3, 3, 100.0)
    w, p, u = s.w.T.copy(), fast.pack(s.P).T.copy(), s.taps.T.copy()
    w, p, u, _ = fast.rls_step(w, p, u, np.array([1.0, 2.0, 3.0]), 0.98,
                               np.array([True, False, True]), 3000.0, 100.0,
                               fill=np.array([9.0, 8.0, 7.0]))
    np.testing.assert_array_equal(u[0], [1.0, 8.0, 3.0])


def test_scalar_kf_equals_batched_kf() -> None:
    rng = np.random.default_rng(3)
    n = 3
    F = np.eye(n) + 0.2 * rng.normal(size=(n, n))
    H = rng.normal(size=(1, n))
    Q = np.diag([0.1, 0.2, 0.3])
    R = np.array([[2.0]])
    x = rng.normal(size=(1, n))
    P = _spd(rng, 1, n)
    xs, Ps = list(x[0]), P[0].tolist()
    for z in rng.normal(size=10):
        x, P = kalman.update(x, P, np.array([[z]]), H, R)
        xs, Ps = scalar.kf_update(xs, Ps, z, list(H[0]), 2.0)
        np.testing.assert_allclose(xs, x[0], rtol=1e-10)
        np.testing.assert_allclose(Ps, P[0], rtol=1e-9, atol=1e-12)
        x, P = kalman.predict(x, P, F, Q)
        xs, Ps = scalar.kf_predict(xs, Ps, F.tolist(), Q.tolist())
        np.testing.assert_allclose(xs, x[0], rtol=1e-10)
        np.testing.assert_allclose(Ps, P[0], rtol=1e-9, atol=1e-12)


def test_scalar_rls_equals_batched_rls_with_guard() -> None:
    rng = np.random.default_rng(4)
    y = np.concatenate([np.cumsum(rng.normal(size=50)), np.full(300, 7.0)])
    s = rls.init(1, 3, 100.0)
    w, P, u = [0.0] * 3, (100.0 * np.eye(3)).tolist(), [0.0] * 3
    for yt in y:
        s, a = rls.update(s, np.array([yt]), 0.9)
        w, P, u, a2 = scalar.rls_update(w, P, u, yt, 1 / 0.9, 3000.0)
        assert a2 == pytest.approx(a[0], rel=1e-8, abs=1e-10)
    np.testing.assert_allclose(w, s.w[0], rtol=1e-8)
    np.testing.assert_allclose(P, s.P[0], rtol=1e-8)


@pytest.mark.slow
def test_million_frames_of_constant_input_stay_finite_and_sensible() -> None:
    # a stopped vehicle: the same position for 10⁶ frames at λ = 0.98 (0.98^-10⁶ would
    # overflow without the trace guard). Pure-Python scalar code keeps this affordable; the
    # test above pins it equal to the batched code, also under the guard.
    a = 412.5
    inv_lam = 1 / 0.98
    w, P, u = [0.0] * 3, (100.0 * np.eye(3)).tolist(), [0.0] * 3
    worst = 0.0
    for n in range(1_000_000):
        w, P, u, _ = scalar.rls_update(w, P, u, a, inv_lam, 3000.0)
        if n > 100 and n % 1000 == 0:
            worst = max(worst, abs(scalar.rls_predict(w, u) - a))
    assert all(math.isfinite(v) for row in P for v in row)
    assert sum(P[i][i] for i in range(3)) <= 3000.0 * (1 + 1e-12)
    assert np.linalg.eigvalsh(np.array(P)).min() > 0
    assert abs(scalar.rls_predict(w, u) - a) < 1e-6
    assert worst < 1e-6
    # and it adapts when the vehicle moves off again (1 px/frame)
    for k in range(1, 60):
        pred = scalar.rls_predict(w, u)
        w, P, u, _ = scalar.rls_update(w, P, u, a + k, inv_lam, 3000.0)
    assert abs(pred - (a + 59)) < 0.5


def test_batched_constant_input_many_frames_stays_finite() -> None:
    # the batched kernel on a batch of stopped vehicles at different positions
    B, T = 64, 5000
    pos = np.linspace(-2000.0, 4000.0, B)
    w = np.zeros((3, B))
    p = np.zeros((6, B))
    p[[0, 3, 5]] = 100.0
    u = np.zeros((3, B))
    ok = np.ones(B, bool)
    for _ in range(T):
        w, p, u, _ = fast.rls_step(w, p, u, pos, 0.98, ok, 3000.0, 100.0)
    pred = (w * u).sum(axis=0)
    assert np.all(np.isfinite(p))
    np.testing.assert_allclose(pred, pos, rtol=1e-9, atol=1e-7)
    assert np.all(p[[0, 3, 5]].sum(axis=0) <= 3000.0 * (1 + 1e-12))
    assert np.linalg.eigvalsh(fast.unpack(p.T, 3)).min() > 0


@pytest.mark.parametrize("kind", ["cv", "ca"])
def test_select_update_equals_generic_kalman_for_coupled_models(kind, chunk) -> None:
    from mvtrack.filters.models import coupled

    model = coupled(kind, 1.0, 0.3, 1.7)
    R = np.array([[1.7, 0.4], [0.4, 2.2]])  # a correlated R exercises the 2×2 inverse
    rng = np.random.default_rng(8)
    B, n = 17, model.n
    x = rng.normal(size=(B, n))
    P = _spd(rng, B, n)
    xc, pc = x.T.copy(), fast.pack(P).T.copy()
    for _ in range(10):
        x, P = kalman.predict(x, P, model.F, model.Q)
        xc, pc = fast.kf_axis_predict(xc, pc, model.F, model.Q)
        z = rng.normal(size=(B, 2)) * 4
        ok = rng.random(B) > 0.3
        z[rng.random(B) < 0.15, 1] = np.nan
        x, P = kalman.update(x, P, z, model.H, R, ok)
        xc, pc = fast.kf_select_update(xc, pc, z.T.copy(), R, ok)
        np.testing.assert_allclose(xc.T, x, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(fast.unpack(pc.T, n), P, rtol=1e-10, atol=1e-12)


def test_select_update_with_one_component_equals_axis_update() -> None:
    rng = np.random.default_rng(9)
    x = rng.normal(size=(3, 5))
    p = fast.pack(_spd(rng, 5, 3)).T.copy()
    z = rng.normal(size=5)
    ok = np.array([True, False, True, True, False])
    xa, pa = fast.kf_axis_update(x, p, z, 2.0, ok)
    xb, pb = fast.kf_select_update(x, p, z[None], np.array([[2.0]]), ok)
    np.testing.assert_allclose(xa, xb, rtol=1e-13)
    np.testing.assert_allclose(pa, pb, rtol=1e-13)
