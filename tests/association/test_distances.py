"""Distances of papers 1 and 2 against hand-computed values and independent references."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import mahalanobis as scipy_mahalanobis

from mvtrack.association.distances import (
    DISTANCES,
    TrackView,
    default_gate,
    distance_matrix,
    pair_distance,
)
from mvtrack.types import Detections

SQ = 1 / np.sqrt(2)


def x6_view(shift: tuple[float, float] = (0.0, 0.0)) -> TrackView:
    """SPEC X6 (paper 2 Fig. 1): target 1 at (0,0) v=(0,1); target 2 at (10,10) v=(1,1)/√2."""
    xy = np.array([[0.0, 0.0], [10.0, 10.0]]) + shift
    return TrackView.from_arrays(xy, cov=1.0, velocity=[[0.0, 1.0], [SQ, SQ]])


Z = np.array([[4.0, 4.0]])


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("euclidean", [32.0, 72.0]),  # eq. (8): 4²+4², 6²+6²
        ("uncoupled", [32.0, 72.0]),  # eq. (9) with P̄ = 1
        ("mahalanobis", [32.0, 72.0]),  # S = P̄ = I
        ("coupled", [20.0, 18.0]),  # SPEC §2.3, ρ = 2: 16/4 + 16/1, 72/4 + 0
        # eq. (10) as printed: a = 4·0 − 4·1, b = 4·1 − 4·0, d = 1 -> (16 + 16)/0.25 = 128;
        # target 2: a = b = 0 -> (100 + 100)/0.25 = 800
        ("coupled-literal", [128.0, 800.0]),
    ],
)
def test_x6_fig1_values(name: str, expected: list[float]) -> None:
    r2 = distance_matrix(name, x6_view(), Z)[:, 0]
    np.testing.assert_allclose(r2, expected, rtol=1e-12, atol=1e-12)


def test_x6_coupled_picks_target_2_uncoupled_picks_target_1() -> None:
    assert np.argmin(distance_matrix("uncoupled", x6_view(), Z)[:, 0]) == 0
    assert np.argmin(distance_matrix("coupled", x6_view(), Z)[:, 0]) == 1


def test_coupled_is_translation_invariant_literal_is_not() -> None:
    shift = (123.0, -45.0)
    for name in ("euclidean", "uncoupled", "coupled", "mahalanobis"):
        a = distance_matrix(name, x6_view(), Z)
        b = distance_matrix(name, x6_view(shift), Z + shift)
        np.testing.assert_allclose(a, b, rtol=1e-9, err_msg=name)
    a = distance_matrix("coupled-literal", x6_view(), Z)
    b = distance_matrix("coupled-literal", x6_view(shift), Z + shift)
    assert not np.allclose(a, b, rtol=1e-3)


def _random_view(rng: np.random.Generator, n: int, diag_equal: bool = False) -> TrackView:
    xy = rng.uniform(0, 100, (n, 2))
    if diag_equal:
        p = rng.uniform(0.5, 5, n)
        cov = p[:, None, None] * np.eye(2)
    else:
        cov = np.zeros((n, 2, 2))
        cov[:, 0, 0] = rng.uniform(0.5, 5, n)
        cov[:, 1, 1] = rng.uniform(0.5, 5, n)
    a = rng.normal(size=(n, 2, 2))
    s = a @ a.transpose(0, 2, 1) + 0.5 * np.eye(2)
    vel = rng.normal(0, 3, (n, 2))
    wh = rng.uniform(5, 40, (n, 2))
    return TrackView(xy, cov, s, vel, wh)


def test_coupled_with_rho_1_reduces_to_eq9() -> None:
    rng = np.random.default_rng(1)
    view = _random_view(rng, 20, diag_equal=True)
    z = rng.uniform(0, 100, (15, 2))
    np.testing.assert_allclose(
        distance_matrix("coupled", view, z, rho=1.0),
        distance_matrix("uncoupled", view, z),
        rtol=1e-12,
    )
    # with ρ = 2 the region is stretched along the velocity, so the values differ
    assert not np.allclose(
        distance_matrix("coupled", view, z), distance_matrix("uncoupled", view, z)
    )


def test_coupled_matches_rotated_covariance_form() -> None:
    """r² = Δᵀ R diag(σ∥², σ⊥²)⁻¹ Rᵀ Δ (SPEC §2.3), computed with explicit matrices."""
    rng = np.random.default_rng(2)
    view = _random_view(rng, 6)
    z = rng.uniform(0, 100, (5, 2))
    got = distance_matrix("coupled", view, z, rho=2.5)
    for i in range(6):
        v = view.velocity[i]
        c, s = v / np.linalg.norm(v)
        rot = np.array([[c, -s], [s, c]])
        sp = 0.5 * (view.cov[i, 0, 0] + view.cov[i, 1, 1])
        cov = rot @ np.diag([2.5**2 * sp, sp]) @ rot.T
        for j in range(5):
            d = z[j] - view.xy[i]
            assert got[i, j] == pytest.approx(d @ np.linalg.solve(cov, d), rel=1e-10)


def test_coupled_falls_back_to_eq9_when_nearly_stationary() -> None:
    view = TrackView(
        np.array([[0.0, 0.0], [0.0, 0.0]]),
        np.array([np.diag([1.0, 4.0]), np.diag([1.0, 4.0])]),
        np.array([np.diag([2.0, 5.0])] * 2),
        np.array([[0.3, 0.2], [0.6, 0.0]]),  # speed 0.36 < 0.5, and 0.6 >= 0.5
        np.zeros((2, 2)),
    )
    z = np.array([[2.0, 2.0]])
    r2 = distance_matrix("coupled", view, z)[:, 0]
    assert r2[0] == pytest.approx(4 / 1 + 4 / 4)  # eq. (9)
    # moving along x: σ⊥² = 2.5, σ∥² = 10: e∥ = 2, e⊥ = 2
    assert r2[1] == pytest.approx(4 / 10 + 4 / 2.5)
    # a smaller threshold turns the fallback off
    assert distance_matrix("coupled", view, z, min_speed=0.1)[0, 0] != pytest.approx(r2[0])


def test_use_innovation_divides_by_s_diagonal() -> None:
    view = TrackView(
        np.zeros((1, 2)),
        np.eye(2)[None],
        np.diag([4.0, 9.0])[None],
        np.zeros((1, 2)),
        np.zeros((1, 2)),
    )
    z = np.array([[2.0, 3.0]])
    assert distance_matrix("uncoupled", view, z)[0, 0] == pytest.approx(13.0)
    assert distance_matrix("uncoupled", view, z, use_innovation=True)[0, 0] == pytest.approx(2.0)
    assert distance_matrix("mahalanobis", view, z)[0, 0] == pytest.approx(2.0)
    assert distance_matrix("mahalanobis", view, z, use_innovation=False)[0, 0] == pytest.approx(
        13.0
    )


def test_mahalanobis_matches_scipy() -> None:
    rng = np.random.default_rng(3)
    view = _random_view(rng, 8)
    z = rng.uniform(0, 100, (7, 2))
    got = distance_matrix("mahalanobis", view, z)
    for i in range(8):
        vi = np.linalg.inv(view.S[i])
        for j in range(7):
            ref = scipy_mahalanobis(z[j], view.xy[i], vi) ** 2
            assert got[i, j] == pytest.approx(ref, rel=1e-10)


def test_iou_hand_values() -> None:
    view = TrackView.from_arrays([[0.0, 0.0]], wh=[2.0, 2.0])
    dets = Detections(
        0, [[1.0, 0.0], [0.0, 0.0], [5.0, 0.0], [0.0, 0.5]], [[2, 2], [2, 2], [2, 2], [1, 1]]
    )
    # overlap 1×2 over union 6; identical; disjoint; a 1×1 box inside: 1/4
    np.testing.assert_allclose(
        distance_matrix("iou", view, dets)[0], [1 - 2 / 6, 0.0, 1.0, 0.75], atol=1e-12
    )


box = st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(0, 30), st.floats(0, 30))


@settings(max_examples=60, deadline=None)
@given(box, box)
def test_iou_in_unit_interval_and_symmetric(a: tuple, b: tuple) -> None:
    va = TrackView.from_arrays([a[:2]], wh=[a[2:]])
    vb = TrackView.from_arrays([b[:2]], wh=[b[2:]])
    ab = distance_matrix("iou", va, Detections(0, [b[:2]], [b[2:]]))[0, 0]
    ba = distance_matrix("iou", vb, Detections(0, [a[:2]], [a[2:]]))[0, 0]
    assert 0.0 <= ab <= 1.0
    assert ab == pytest.approx(ba, abs=1e-12)


def test_default_gates() -> None:
    assert default_gate("euclidean") == 100.0  # a 10 px circle
    for name in ("uncoupled", "coupled", "coupled-literal", "mahalanobis"):
        assert default_gate(name) == 9.21
    assert default_gate("iou") == 0.7


def test_pairs_equal_dense_entries() -> None:
    rng = np.random.default_rng(5)
    view = _random_view(rng, 9)
    z = rng.uniform(0, 100, (11, 2))
    ti = rng.integers(0, 9, 30)
    dj = rng.integers(0, 11, 30)
    for name in DISTANCES:
        np.testing.assert_array_equal(
            pair_distance(name, view, z, ti, dj), distance_matrix(name, view, z)[ti, dj]
        )


def test_bad_input_raises_value_error() -> None:
    with pytest.raises(ValueError, match="unknown distance"):
        distance_matrix("manhattan", x6_view(), Z)
    with pytest.raises(ValueError, match="unknown parameter"):
        distance_matrix("euclidean", x6_view(), Z, rho=2.0)
    with pytest.raises(ValueError, match="rho must be positive"):
        distance_matrix("coupled", x6_view(), Z, rho=0.0)
    with pytest.raises(ValueError, match=r"TrackView\.cov"):
        TrackView(
            np.zeros((2, 2)),
            np.zeros((3, 2, 2)),
            np.zeros((2, 2, 2)),
            np.zeros((2, 2)),
            np.zeros((2, 2)),
        )
    with pytest.raises(ValueError, match="dets must be"):
        distance_matrix("euclidean", x6_view(), np.zeros((3, 3)))


def test_track_view_from_predictor() -> None:
    from mvtrack.filters.predictors import make_predictor

    pred = make_predictor("kalman-cv", q=0.1, r=4.0)
    state = pred.predict(pred.init(np.array([[10.0, 20.0], [30.0, 40.0]])))
    view = TrackView.from_predictor(pred, state, np.full((2, 2), 8.0))
    np.testing.assert_allclose(view.xy, [[10.0, 20.0], [30.0, 40.0]])
    np.testing.assert_allclose(view.S, view.cov + 4.0 * np.eye(2))
    z = np.array([[12.0, 21.0]])
    d = distance_matrix("mahalanobis", view, z)[0, 0]
    assert d == pytest.approx(np.array([2.0, 1.0]) @ np.linalg.solve(view.S[0], [2.0, 1.0]))
