"""The tracker-facing predictors: protocol, batching, masks, equality with the generic filters."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.filters import kalman, rls
from mvtrack.filters.base import Predictor
from mvtrack.filters.models import constant_acceleration, coupled
from mvtrack.filters.predictors import PREDICTORS, RLSPredictor, make_predictor
from mvtrack.types import concat_rows, n_rows, take_rows


def _tracks(rng: np.random.Generator, N: int, T: int) -> np.ndarray:
    v = rng.normal(0, 2, size=(N, 2))
    start = rng.uniform(0, 300, size=(N, 2))
    t = np.arange(T)[:, None, None]
    return start + v * t + 0.02 * t**2 + rng.normal(0, 1, size=(T, N, 2))


@pytest.mark.parametrize("name", list(PREDICTORS))
def test_every_predictor_implements_the_protocol_and_batches(name: str) -> None:
    rng = np.random.default_rng(0)
    p = make_predictor(name)
    assert isinstance(p, Predictor) and p.name == name
    z = _tracks(rng, 6, 25)
    s = p.init(z[0])
    for t in range(1, 25):
        s = p.predict(s)
        assert p.position(s).shape == (6, 2) and p.velocity(s).shape == (6, 2)
        for cov in (p.position_cov(s), p.innovation_cov(s)):
            assert cov.shape == (6, 2, 2)
            np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2))
            assert np.all(np.linalg.eigvalsh(cov) > 0)
        assert np.all(np.linalg.eigvalsh(p.innovation_cov(s) - p.position_cov(s)) > 0)
        s = p.update(s, z[t], rng.random(6) > 0.1)
    # after 25 frames the prediction is within a few pixels
    s = p.predict(s)
    truth_next = z[24] + (z[24] - z[23])
    assert np.abs(p.position(s) - truth_next).max() < 15
    # rows are independent: a batch equals its rows run one by one
    s2 = p.init(z[0, 2:3])
    rng2 = np.random.default_rng(0)
    _ = _tracks(rng2, 6, 25)
    masks = rng2.random((24, 6)) > 0.1
    s_all = p.init(z[0])
    for t in range(1, 25):
        s_all = p.update(p.predict(s_all), z[t], masks[t - 1])
        s2 = p.update(p.predict(s2), z[t, 2:3], masks[t - 1, 2:3])
    np.testing.assert_allclose(p.position(take_rows(s_all, np.array([2]))), p.position(s2),
                               rtol=1e-12)
    both = concat_rows(s_all, s2)
    assert n_rows(both) == 7
    np.testing.assert_allclose(p.position(both)[6], p.position(s2)[0])


@pytest.mark.parametrize("name", list(PREDICTORS))
def test_masked_and_nan_rows_keep_the_prediction(name: str) -> None:
    p = make_predictor(name)
    s = p.init(np.array([[10.0, 10.0], [50.0, 60.0], [0.0, 0.0]]))
    for k in range(1, 8):
        s = p.update(p.predict(s), np.array([[10.0 + k, 10.0], [50.0, 60.0 - k], [k, k]]),
                     np.ones(3, bool))
    s = p.predict(s)
    before = p.position(s)
    z = np.array([[99.0, 99.0], [np.nan, 1.0], [30.0, 30.0]])
    s2 = p.update(s, z, np.array([False, True, True]))
    after = p.position(s2)
    if name == "rls":
        # RLS coasts: the reported prediction enters the delay line
        np.testing.assert_allclose(after[:2], before[:2])
    else:
        np.testing.assert_array_equal(after[:2], before[:2])
    assert np.all(np.isfinite(after))
    assert np.abs(after[2] - before[2]).max() > 1.0


def test_per_axis_ca_equals_generic_kalman_on_each_axis() -> None:
    rng = np.random.default_rng(4)
    p = make_predictor("kalman-ca", q=0.3, r=2.0, vel_var=9.0, acc_var=0.5)
    model = constant_acceleration(1.0, 0.3, 2.0)
    z = _tracks(rng, 5, 30)
    masks = rng.random((30, 5)) > 0.2
    s = p.init(z[0])
    x = np.zeros((10, 3))
    x[:, 0] = z[0].reshape(10)
    P = np.broadcast_to(np.diag([2.0, 9.0, 0.5]), (10, 3, 3)).copy()
    for t in range(1, 30):
        s = p.predict(s)
        x, P = kalman.predict(x, P, model.F, model.Q)
        np.testing.assert_allclose(s.x.reshape(10, 3), x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(p.covariance(s).reshape(10, 3, 3), P, rtol=1e-10, atol=1e-10)
        s = p.update(s, z[t], masks[t])
        x, P = kalman.update(x, P, z[t].reshape(10, 1), model.H, model.R, np.repeat(masks[t], 2))
        np.testing.assert_allclose(s.x.reshape(10, 3), x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(p.covariance(s).reshape(10, 3, 3), P, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(p.innovation_cov(s)[:, 0, 0], P[0::2, 0, 0] + 2.0)


def test_coupled_equals_generic_kalman() -> None:
    rng = np.random.default_rng(5)
    p = make_predictor("kalman-coupled", q=0.2, r=1.5)
    model = coupled("cv", 1.0, 0.2, 1.5)
    z = _tracks(rng, 4, 20)
    s = p.init(z[0])
    x = np.zeros((4, 4))
    x[:, :2] = z[0]
    P = np.broadcast_to(np.diag([1.5, 1.5, 25.0, 25.0]), (4, 4, 4)).copy()
    for t in range(1, 20):
        s = p.update(p.predict(s), z[t], np.ones(4, bool))
        x, P = kalman.update(*kalman.predict(x, P, model.F, model.Q), z[t], model.H, model.R)
    np.testing.assert_allclose(s.x, x, rtol=1e-10)
    np.testing.assert_allclose(p.covariance(s), P, rtol=1e-10)
    np.testing.assert_allclose(p.position_cov(s), P[:, :2, :2], rtol=1e-10)
    np.testing.assert_allclose(p.innovation_cov(s), P[:, :2, :2] + 1.5 * np.eye(2), rtol=1e-10)


def test_rls_predictor_equals_rls_module_after_warmup() -> None:
    rng = np.random.default_rng(6)
    p = RLSPredictor(M=3, lam=0.95, c=50.0, warmup=0)
    z = _tracks(rng, 3, 40)
    s = p.init(z[0])
    st = rls.init(6, 3, 50.0)
    st, _ = rls.update(st, z[0].reshape(6), 0.95, c=50.0)
    for t in range(1, 40):
        s = p.predict(s)
        np.testing.assert_allclose(p.position(s).reshape(6), rls.predict(st), rtol=1e-9)
        s = p.update(s, z[t], np.ones(3, bool))
        st, _ = rls.update(st, z[t].reshape(6), 0.95, c=50.0)
    np.testing.assert_allclose(s.w.reshape(6, 3), st.w, rtol=1e-8, atol=1e-10)


def test_rls_warmup_extrapolates_linearly() -> None:
    p = RLSPredictor()  # warm-up 2M = 6
    s = p.init(np.array([[5.0, 7.0]]))
    s = p.predict(s)
    np.testing.assert_array_equal(p.position(s), [[5.0, 7.0]])  # y_k after one association
    s = p.update(s, np.array([[8.0, 6.0]]), np.ones(1, bool))
    s = p.predict(s)
    np.testing.assert_array_equal(p.position(s), [[11.0, 5.0]])  # 2 y_k − y_{k−1}
    np.testing.assert_array_equal(p.velocity(s), [[3.0, -1.0]])


def test_unknown_name_lists_known_predictors() -> None:
    with pytest.raises(ValueError, match=r"kalman-ca.*kalman-cv.*kalman-coupled.*rls"):
        make_predictor("particle")


@pytest.mark.parametrize(
    "name, params, match",
    [
        ("kalman-ca", {"q": -1.0}, "q"),
        ("kalman-ca", {"r": 0.0}, "r"),
        ("kalman-cv", {"vel_var": np.nan}, "vel_var"),
        ("kalman-coupled", {"kind": "cj"}, "kind"),
        ("rls", {"M": 0}, "M"),
        ("rls", {"lam": 1.5}, "lam"),
        ("rls", {"c": -2.0}, "c"),
        ("rls", {"beta": 2.0}, "beta"),
        ("rls", {"bogus": 1}, "bogus"),
    ],
)
def test_bad_parameters_raise_value_error(name, params, match) -> None:
    with pytest.raises(ValueError, match=match):
        make_predictor(name, **params)


@pytest.mark.parametrize("name", list(PREDICTORS))
def test_bad_measurement_shapes_raise(name: str) -> None:
    p = make_predictor(name)
    s = p.init(np.zeros((2, 2)))
    with pytest.raises(ValueError, match="z"):
        p.update(s, np.zeros((3, 2)), np.ones(2, bool))
    with pytest.raises(ValueError, match="mask"):
        p.update(s, np.zeros((2, 2)), np.ones(2))
    with pytest.raises(ValueError, match="xy"):
        p.init(np.zeros((2, 3)))


@settings(max_examples=25, deadline=None)
@given(
    name=st.sampled_from(sorted(PREDICTORS)),
    N=st.integers(0, 7),
    steps=st.integers(1, 15),
    seed=st.integers(0, 2**31 - 1),
)
def test_property_shapes_covariances_and_masks(name, N, steps, seed) -> None:
    rng = np.random.default_rng(seed)
    p = make_predictor(name)
    s = p.init(rng.uniform(0, 500, size=(N, 2)))
    for _ in range(steps):
        s = p.predict(s)
        before = p.position(s)
        for cov in (p.position_cov(s), p.innovation_cov(s)):
            assert cov.shape == (N, 2, 2)
            np.testing.assert_allclose(cov, np.swapaxes(cov, 1, 2), rtol=1e-12, atol=1e-12)
            if N:
                assert np.linalg.eigvalsh(cov).min() > 0
        z = before + rng.normal(0, 3, size=(N, 2))
        z[rng.random(N) < 0.2, rng.integers(0, 2)] = np.nan
        mask = rng.random(N) > 0.2
        s = p.update(s, z, mask)
        after = p.position(s)
        missing = ~(mask & np.isfinite(z).all(axis=1))
        np.testing.assert_allclose(after[missing], before[missing], rtol=1e-12, atol=1e-9)
        assert np.all(np.isfinite(after)) and np.all(np.isfinite(p.velocity(s)))
        assert n_rows(s) == N
    # take/concat keep rows intact
    if N:
        idx = rng.permutation(N)
        shuffled = take_rows(s, idx)
        np.testing.assert_array_equal(p.position(shuffled), p.position(s)[idx])
        np.testing.assert_array_equal(p.position(p.predict(shuffled)),
                                      p.position(p.predict(s))[idx])


def test_rls_history_parameter_sets_samples_before_the_first() -> None:
    xy = np.array([[120.0, 80.0]])
    zeros = RLSPredictor(warmup=0)  # SPEC §1.3 [R]: samples before the first are 0
    s = zeros.predict(zeros.init(xy))
    np.testing.assert_array_equal(zeros.position(s), [[0.0, 0.0]])  # ỹ₁ = 0: ŵ stays 0
    first = RLSPredictor(warmup=0, history="first")
    s = first.predict(first.init(xy))
    np.testing.assert_allclose(first.position(s), xy, rtol=1e-4)
    with pytest.raises(ValueError, match="history"):
        RLSPredictor(history="ones")


def test_rls_error_variance_is_a_floored_running_mean_of_squared_errors() -> None:
    p = RLSPredictor(r=2.0, vel_var=10.0, beta=0.5, min_var=0.25, warmup=100)
    s = p.init(np.array([[0.0, 0.0]]))
    np.testing.assert_allclose(p.innovation_cov(s)[0], 12.0 * np.eye(2))  # r + vel_var
    s = p.predict(s)  # warm-up prediction: the last position, (0, 0)
    s = p.update(s, np.array([[4.0, 0.0]]), np.ones(1, bool))
    # e = 0.5·12 + 0.5·16 = 14 on x; 0.5·12 + 0 = 6 on y
    np.testing.assert_allclose(np.diagonal(p.innovation_cov(s)[0]), [14.0, 6.0])
    np.testing.assert_allclose(np.diagonal(p.position_cov(s)[0]), [12.0, 4.0])
    for _ in range(30):  # perfect predictions drive e to 0; P̄ stops at min_var
        s = p.predict(s)
        s = p.update(s, p.position(s), np.ones(1, bool))
    np.testing.assert_allclose(np.diagonal(p.position_cov(s)[0]), [0.25, 0.25])
    np.testing.assert_allclose(np.diagonal(p.innovation_cov(s)[0]), [2.25, 2.25])
