"""``kalman-cv`` (:class:`mvtrack.filters.cv.KalmanCVPredictor`, the closed-form per-axis CV
Kalman filter) equals the general per-axis Kalman filter of :mod:`mvtrack.filters.predictors`
on the same model (the oracle), also with a measurement variance per track."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.filters.cv import KalmanCVPredictor
from mvtrack.filters.models import constant_velocity
from mvtrack.filters.predictors import PerAxisKalmanPredictor, make_predictor


def _general_cv(
    q: float = 0.1, r: float = 1.0, vel_var: float = 25.0, dt: float = 1.0
) -> PerAxisKalmanPredictor:
    """The oracle: the general per-axis Kalman filter on ``kalman-cv``'s model."""
    return PerAxisKalmanPredictor(constant_velocity(dt, q, r), vel_var, name="kalman-cv")


def test_make_predictor_kalman_cv_is_the_closed_form() -> None:
    assert type(make_predictor("kalman-cv", q=0.3)) is KalmanCVPredictor


@pytest.mark.parametrize(
    "params", [{}, {"q": 0.3, "r": 4.0, "vel_var": 9.0}, {"q": 0.3, "dt": 0.5}]
)
def test_fast_cv_equals_the_general_kalman_cv_over_a_random_run(params: dict) -> None:
    rng = np.random.default_rng(5)
    fast = KalmanCVPredictor(**params)
    ref = _general_cv(**params)
    xy0 = rng.uniform(0, 500, (6, 2))
    a, b = fast.init(xy0), ref.init(xy0)
    for k in range(40):
        a, b = fast.predict(a), ref.predict(b)
        np.testing.assert_allclose(fast.position(a), ref.position(b), rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(fast.innovation_cov(a), ref.innovation_cov(b), rtol=1e-10)
        np.testing.assert_allclose(fast.position_cov(a), ref.position_cov(b), rtol=1e-10)
        z = xy0 + k * 2.0 + rng.normal(0, 2.0, xy0.shape)
        mask = rng.random(6) > 0.3
        z[~mask & (rng.random(6) > 0.5)] = np.nan  # some missing rows say so with NaN
        a, b = fast.update(a, z, mask), ref.update(b, z, mask)
        np.testing.assert_allclose(fast.position(a), ref.position(b), rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(fast.velocity(a), ref.velocity(b), rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(
            fast.position_cov(a), ref.position_cov(b), rtol=1e-9, atol=1e-12
        )
        np.testing.assert_allclose(fast.covariance(a), ref.covariance(b), rtol=1e-9, atol=1e-9)


def test_fast_cv_rows_without_measurement_keep_the_prediction() -> None:
    f = KalmanCVPredictor(q=0.5, r=2.0)
    s = f.predict(f.init(np.array([[0.0, 0.0], [10.0, 10.0]])))
    z = np.array([[1.0, 1.0], [np.nan, np.nan]])
    u = f.update(s, z, np.array([True, True]))
    np.testing.assert_array_equal(u.x[1], s.x[1])
    np.testing.assert_array_equal(u.P[1], s.P[1])
    assert not np.array_equal(u.x[0], s.x[0])


def test_fast_cv_with_per_track_r_equals_kalman_cv_with_each_r() -> None:
    rng = np.random.default_rng(3)
    fast = KalmanCVPredictor(q=0.2, r=4.0, vel_var=9.0)
    r = np.array([4.0, 36.0, 100.0])
    refs = [_general_cv(q=0.2, r=float(v), vel_var=9.0) for v in r]
    xy0 = rng.uniform(0, 300, (3, 2))
    a = fast.init(xy0, r)
    b = [p.init(xy0[i : i + 1]) for i, p in enumerate(refs)]
    for k in range(25):
        a = fast.predict(a)
        b = [p.predict(s) for p, s in zip(refs, b, strict=True)]
        z = xy0 + 3.0 * k + rng.normal(0, 3.0, xy0.shape)
        mask = rng.random(3) > 0.2
        a = fast.update(a, z, mask, r)
        b = [p.update(s, z[i : i + 1], mask[i : i + 1]) for i, (p, s) in
             enumerate(zip(refs, b, strict=True))]
        for i, (p, s) in enumerate(zip(refs, b, strict=True)):
            np.testing.assert_allclose(fast.position(a)[i], p.position(s)[0], rtol=1e-10)
            np.testing.assert_allclose(fast.velocity(a)[i], p.velocity(s)[0], atol=1e-9)
            np.testing.assert_allclose(fast.position_cov(a)[i], p.position_cov(s)[0],
                                       rtol=1e-9)


def test_per_axis_noise_equals_filterpy_per_axis() -> None:
    """Each axis with its own r and q (the tracker's box-size noise: x by the width, y by the
    height) equals two 1-D filterpy Kalman filters with those values."""
    from filterpy.common import Q_discrete_white_noise
    from filterpy.kalman import KalmanFilter

    rng = np.random.default_rng(8)
    r, q, vv = np.array([[2.0, 30.0]]), np.array([[0.02, 0.7]]), np.array([[4.0, 49.0]])
    fast = KalmanCVPredictor()
    s = fast.init(np.array([[5.0, 7.0]]), r, vv)
    refs = []
    for ax, start in enumerate((5.0, 7.0)):
        f = KalmanFilter(dim_x=2, dim_z=1)
        f.F = np.array([[1.0, 1.0], [0.0, 1.0]])
        f.H = np.array([[1.0, 0.0]])
        f.R = np.array([[r[0, ax]]])
        f.Q = Q_discrete_white_noise(dim=2, dt=1.0, var=q[0, ax])
        f.x = np.array([start, 0.0])
        f.P = np.diag([r[0, ax], vv[0, ax]])
        refs.append(f)
    for k in range(40):
        s = fast.predict(s, q)
        for f in refs:
            f.predict()
        z = np.array([[5.0 + 1.2 * k, 7.0 - 0.8 * k]]) + rng.normal(0, 1.5, (1, 2))
        s = fast.update(s, z, np.array([k % 5 != 2]), r)
        for ax, f in enumerate(refs):
            if k % 5 != 2:
                f.update(z[0, ax])
            np.testing.assert_allclose(s.x[0, [ax, 2 + ax]], f.x, rtol=1e-10, atol=1e-10)
            np.testing.assert_allclose(s.P[0, ax], [f.P[0, 0], f.P[0, 1], f.P[1, 1]],
                                       rtol=1e-10, atol=1e-12)


def test_the_compiled_kernels_equal_their_plain_functions() -> None:
    from mvtrack.filters.cv import cv_predict, cv_update

    rng = np.random.default_rng(9)
    n = 30
    s = KalmanCVPredictor().init(rng.uniform(0, 100, (n, 2)), rng.uniform(1, 9, (n, 2)),
                                 rng.uniform(1, 30, (n, 2)))
    q, r = rng.uniform(0.01, 2, (n, 2)), rng.uniform(1, 9, (n, 2))
    z, mask = rng.uniform(0, 100, (n, 2)), rng.random(n) > 0.3
    for a, b in zip(cv_predict(s.x, s.P, q, 1.0), cv_predict.py_func(s.x, s.P, q, 1.0),
                    strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(cv_update(s.x, s.P, z, mask, r), cv_update.py_func(s.x, s.P, z, mask, r),
                    strict=True):
        np.testing.assert_array_equal(a, b)
