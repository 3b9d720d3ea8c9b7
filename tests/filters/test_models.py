"""Motion models: the matrices of paper 1 eqs. (8)–(9), the CV and coupled variants, validation."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.filters.models import LinearModel, constant_acceleration, constant_velocity, coupled


def test_constant_acceleration_is_eqs_8_and_9() -> None:
    m = constant_acceleration(dt=0.5, q=0.7, r=3.0)
    np.testing.assert_array_equal(m.F, [[1, 0.5, 0.125], [0, 1, 0.5], [0, 0, 1]])
    np.testing.assert_array_equal(m.H, [[1, 0, 0]])
    np.testing.assert_array_equal(m.Q, np.diag([0, 0, 0.7]))  # G q Gᵀ, G = [0, 0, 1]ᵀ (E1.7)
    np.testing.assert_array_equal(m.R, [[3.0]])
    assert (m.n, m.m) == (3, 1)


@pytest.mark.parametrize("make", [constant_acceleration, constant_velocity])
def test_transition_is_exact_polynomial_motion(make) -> None:
    # F(dt)^k = F(k dt): integrating k small steps equals one big step
    small, big = make(dt=0.25), make(dt=1.0)
    np.testing.assert_allclose(np.linalg.matrix_power(small.F, 4), big.F, rtol=1e-15)
    # a noise-free quadratic (or linear) path is propagated exactly
    x = np.array([2.0, -1.0, 0.5])[: big.n]
    t = np.arange(6.0)
    path = [x[0] + x[1] * tt + (0.5 * x[2] * tt**2 if big.n == 3 else 0.0) for tt in t]
    for k in range(6):
        assert x[0] == pytest.approx(path[k], rel=1e-14)
        x = big.F @ x


def test_constant_velocity_noise_is_white_acceleration() -> None:
    m = constant_velocity(dt=2.0, q=0.3, r=1.0)
    G = np.array([2.0, 2.0])  # [dt²/2, dt]
    np.testing.assert_allclose(m.Q, 0.3 * np.outer(G, G), rtol=1e-15)
    np.testing.assert_array_equal(m.F, [[1, 2.0], [0, 1]])


@pytest.mark.parametrize("kind,n", [("cv", 4), ("ca", 6)])
def test_coupled_model_orders_state_by_derivative_then_axis(kind: str, n: int) -> None:
    m = coupled(kind, dt=1.0, q=0.2, r=2.0)
    assert (m.n, m.m) == (n, 2)
    np.testing.assert_array_equal(m.H, np.eye(n)[:2])
    np.testing.assert_array_equal(m.R, 2.0 * np.eye(2))
    x = np.zeros(n)
    x[:4] = [10.0, 20.0, 1.0, -2.0]  # x, y, vx, vy
    np.testing.assert_allclose((m.F @ x)[:2], [11.0, 18.0])
    axis = (constant_velocity if kind == "cv" else constant_acceleration)(1.0, 0.2, 2.0)
    # x and y blocks are the per-axis model
    np.testing.assert_array_equal(m.F[0::2, 0::2], axis.F)
    np.testing.assert_array_equal(m.Q[1::2, 1::2], axis.Q)
    np.testing.assert_array_equal(m.Q[0::2, 1::2], 0.0)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: constant_acceleration(q=0.0), "q"),
        (lambda: constant_acceleration(q=-1.0), "q"),
        (lambda: constant_acceleration(r=np.nan), "r"),
        (lambda: constant_velocity(dt=np.inf), "dt"),
        (lambda: constant_velocity(dt="fast"), "dt"),
        (lambda: coupled("cj"), "kind"),
        (lambda: LinearModel(np.eye(2), np.eye(2)[:1], np.eye(3), np.eye(1)), "Q"),
        (lambda: LinearModel(np.eye(2), np.eye(3)[:1], np.eye(2), np.eye(1)), "H"),
        (lambda: LinearModel(np.ones(2), np.eye(2)[:1], np.eye(2), np.eye(1)), "F"),
        (lambda: LinearModel(np.eye(2), np.eye(2)[:1], np.eye(2), np.zeros((1, 1))), "R"),
        (lambda: LinearModel(np.eye(2), np.eye(2)[:1], [[1, 2], [0, 1]], np.eye(1)), "Q"),
        (lambda: LinearModel(np.eye(2), np.eye(2)[:1], -np.eye(2), np.eye(1)), "Q"),
        (lambda: LinearModel(np.full((2, 2), np.nan), np.eye(2)[:1], np.eye(2), np.eye(1)), "F"),
    ],
)
def test_bad_parameters_raise_value_error_naming_them(call, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        call()


def test_model_matrices_are_read_only() -> None:
    m = constant_acceleration()
    with pytest.raises(ValueError):
        m.F[0, 0] = 2.0
