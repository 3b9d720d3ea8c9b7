"""``kalman-imm``: against filterpy's IMM estimator, against the CV filter it reduces to, the
compiled kernels against their plain functions, and the manoeuvre it is for."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import IMMEstimator, KalmanFilter

from mvtrack.filters.cv import KalmanCVPredictor
from mvtrack.filters.imm import IMMState, KalmanIMMPredictor, imm_predict, imm_update


def _filterpy_imm(xy0, r, vel_var, q, switch) -> IMMEstimator:
    """filterpy's IMM of two 4-state CV filters [x, vx, y, vy] with noise ``q`` (2,) and
    measurement variances ``r`` (2,) per axis."""
    filters = []
    for qi in q:
        f = KalmanFilter(dim_x=4, dim_z=2)
        f.F = np.array([[1.0, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]])
        f.H = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0]])
        f.R = np.diag(r)
        blk = Q_discrete_white_noise(dim=2, dt=1.0, var=qi)  # G q Gᵀ, G = [1/2, 1]
        f.Q = np.zeros((4, 4))
        f.Q[:2, :2] = f.Q[2:, 2:] = blk
        f.x = np.array([xy0[0], 0.0, xy0[1], 0.0])
        f.P = np.diag([r[0], vel_var[0], r[1], vel_var[1]])
        filters.append(f)
    a, b = switch
    M = np.array([[1 - a, a], [b, 1 - b]])
    mu = np.array([b / (a + b), a / (a + b)])
    return IMMEstimator(filters, mu, M)


def test_equals_filterpy_imm_on_motion_along_one_axis() -> None:
    """With the motion along x only (y measured where it starts), the two models never differ
    along y, the cross-axis terms of the mixing vanish and the per-axis IMM is the 4-state
    IMM exactly: every model's prior and posterior, and the mode probabilities."""
    rng = np.random.default_rng(0)
    r, vv, q, switch = np.array([4.0, 9.0]), np.array([25.0, 16.0]), (0.01, 2.0), (0.02, 0.2)
    ours = KalmanIMMPredictor(q=q[0], q_manoeuvre=q[1], switch=switch)
    s = ours.init(np.array([[10.0, 50.0]]), r[None], vv[None])
    ref = _filterpy_imm((10.0, 50.0), r, vv, q, switch)
    x = 10.0
    v = 1.5
    for k in range(60):
        if k == 30:
            v = -2.0  # a turn back: the manoeuvre model takes over
        x += v
        s = ours.predict(s)
        ref.predict()
        for j, f in enumerate(ref.filters):
            np.testing.assert_allclose(s.x[0, j], f.x[[0, 2, 1, 3]], rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(s.P[0, j, 0], [f.P[0, 0], f.P[0, 1], f.P[1, 1]],
                                       rtol=1e-9)
        np.testing.assert_allclose(s.mu[0], ref.cbar, rtol=1e-9)
        if k % 7 == 3:  # a missed detection: the filters coast and μ = c (filterpy's update
            ref.mu = ref.cbar.copy()  # would leave μ at its last posterior; this is the IMM's
            ref._compute_mixing_probabilities()  # no-measurement step)
            continue
        z = np.array([[x + rng.normal(0, 2.0), 50.0]])
        s = ours.update(s, z, np.array([True]), r[None])
        ref.update(z[0])
        np.testing.assert_allclose(s.mu[0], ref.mu, rtol=1e-9, atol=1e-12)
        for j, f in enumerate(ref.filters):
            np.testing.assert_allclose(s.x[0, j], f.x[[0, 2, 1, 3]], rtol=1e-9, atol=1e-9)
    assert s.mu[0, 1] > 0.5 or ref.mu[1] > 0.0  # the run reached the manoeuvre


def test_a_missed_detection_keeps_the_predicted_mode_probabilities() -> None:
    p = KalmanIMMPredictor(q=0.01, q_manoeuvre=1.0, switch=(0.05, 0.3))
    s = p.predict(p.init(np.array([[0.0, 0.0]])))
    u = p.update(s, np.array([[np.nan, np.nan]]), np.array([True]))
    np.testing.assert_array_equal(u.mu, s.mu)
    np.testing.assert_array_equal(u.x, s.x)


def test_without_switching_it_is_the_cv_filter() -> None:
    """Never leaving the steady mode, the IMM is the CV filter with the steady noise."""
    rng = np.random.default_rng(1)
    imm = KalmanIMMPredictor(q=0.05, q_manoeuvre=5.0, r=3.0, vel_var=16.0, switch=(0.0, 1.0))
    cv = KalmanCVPredictor(q=0.05, r=3.0, vel_var=16.0)
    xy0 = rng.uniform(0, 100, (5, 2))
    a, b = imm.init(xy0), cv.init(xy0)
    for k in range(30):
        a, b = imm.predict(a), cv.predict(b)
        np.testing.assert_allclose(imm.position(a), cv.position(b), rtol=1e-12)
        np.testing.assert_allclose(imm.position_cov(a), cv.position_cov(b), rtol=1e-12)
        z = xy0 + 2.0 * k + rng.normal(0, 2, xy0.shape)
        mask = rng.random(5) > 0.2
        a, b = imm.update(a, z, mask), cv.update(b, z, mask)
        np.testing.assert_allclose(imm.velocity(a), cv.velocity(b), rtol=1e-10, atol=1e-12)


def test_the_compiled_kernels_equal_their_plain_functions() -> None:
    rng = np.random.default_rng(2)
    n = 40
    p = KalmanIMMPredictor()
    s = p.init(rng.uniform(0, 500, (n, 2)), rng.uniform(1, 9, (n, 2)), rng.uniform(1, 50, (n, 2)))
    q = rng.uniform(0.001, 3.0, (n, 2, 2))
    pi = p.transitions()
    z = rng.uniform(0, 500, (n, 2))
    mask = rng.random(n) > 0.3
    r = rng.uniform(1, 9, (n, 2))
    for _ in range(5):
        out = imm_predict(s.x, s.P, s.mu, q, pi)
        ref = imm_predict.py_func(s.x, s.P, s.mu, q, pi)
        for a, b in zip(out, ref, strict=True):
            np.testing.assert_array_equal(a, b)
        s = IMMState(*out)
        out = imm_update(s.x, s.P, s.mu, z, mask, r)
        ref = imm_update.py_func(s.x, s.P, s.mu, z, mask, r)
        for a, b in zip(out, ref, strict=True):
            np.testing.assert_array_equal(a, b)
        s = IMMState(*out)


@pytest.mark.parametrize("fps", [10.0, 30.0])
def test_a_turn_moves_the_track_to_the_manoeuvre_mode_and_back(fps: float) -> None:
    """A steady walker keeps the steady mode; a sharp turn back raises the manoeuvre mode's
    probability above one half within a few frames; steady again, it falls back."""
    from mvtrack.tracking.config import TrackerConfig

    c = TrackerConfig(fps=fps)
    p = KalmanIMMPredictor(switch=c.mode_switching())
    wh = np.array([[40.0, 100.0]])
    r, vv = c.noise(wh)
    q0, q1 = c.accelerations(wh)
    s = p.init(np.array([[100.0, 100.0]]), r, vv)
    x, v = 100.0, 60.0 / fps  # 1.5 box widths per second
    modes = []
    for k in range(int(4 * fps)):
        if k == int(2 * fps):
            v = -v
        x += v
        s = p.predict(s, q0, q1)
        s = p.update(s, np.array([[x, 100.0]]), np.array([True]), r)
        modes.append(s.mu[0, 1])
    turn = int(2 * fps)
    assert max(modes[turn - 5 : turn]) < 0.2
    assert max(modes[turn : turn + 4]) > 0.5
    assert modes[-1] < 0.2
