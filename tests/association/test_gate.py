"""The gate: its quadratic forms are the distances of papers 1 and 2, its pairs are the pairs
inside it, its regions are the ones it applies, and paper 1's warm-up centre by hand."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association.distances import distance_matrix
from mvtrack.association.gate import QUADRATIC, Gate, shapes, warmup_centre
from mvtrack.association.view import TrackView
from mvtrack.types import Detections


def _view(rng: np.random.Generator, n: int) -> TrackView:
    """Tracks with anisotropic, correlated P̄ and S, some slow (coupled falls back)."""
    a = rng.uniform(1, 40, n)
    c = rng.uniform(1, 40, n)
    b = rng.uniform(-0.9, 0.9, n) * np.sqrt(a * c)
    cov = np.stack([np.stack([a, b], -1), np.stack([b, c], -1)], -2)
    S = cov + rng.uniform(1, 9, n)[:, None, None] * np.eye(2)
    v = rng.normal(0, 3, (n, 2))
    v[: n // 4] *= 0.05  # below min_speed: the coupled gate is eq. (9)'s
    return TrackView(rng.uniform(0, 200, (n, 2)), cov, S, v, rng.uniform(10, 60, (n, 2)))


@pytest.mark.parametrize(
    "distance,params",
    [
        ("mahalanobis", {}),
        ("mahalanobis", {"use_innovation": False}),
        ("euclidean", {}),
        ("uncoupled", {}),
        ("uncoupled", {"use_innovation": True}),
        ("coupled", {}),
        ("coupled", {"rho": 3.0, "min_speed": 1.0}),
    ],
)
def test_the_quadratic_gate_is_the_distance(distance: str, params: dict) -> None:
    """``(z − c)ᵀ C⁻¹ (z − c)`` with the gate's covariance equals the distance of
    :mod:`mvtrack.association.distances` for every pair, to rounding."""
    rng = np.random.default_rng(3)
    view = _view(rng, 30)
    z = rng.uniform(-20, 220, (25, 2))
    wh = rng.uniform(10, 60, (25, 2))
    gate = Gate.build(distance, view, 9.21, **params)
    assert gate.quadratic
    np.testing.assert_allclose(gate.matrix(z, wh),
                               distance_matrix(distance, view, Detections(0, z, wh), **params),
                               rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("distance", ["iou", "coupled-literal"])
def test_the_other_gates_are_their_distance_matrices(distance: str) -> None:
    rng = np.random.default_rng(4)
    view = _view(rng, 12)
    z = view.xy[rng.integers(0, 12, 15)] + rng.normal(0, 5, (15, 2))
    wh = rng.uniform(10, 60, (15, 2))
    gate = Gate.build(distance, view, 0.7 if distance == "iou" else 9.21)
    assert not gate.quadratic
    np.testing.assert_array_equal(gate.matrix(z, wh),
                                  distance_matrix(distance, view, Detections(0, z, wh)))
    assert np.isnan(gate.regions(np.arange(12), np.arange(12)).shape).all()  # drawn as nothing


def test_the_size_term_adds_the_weighted_squared_log_ratios() -> None:
    view = TrackView.from_arrays([[0.0, 0.0]], cov=4.0, wh=[[20.0, 40.0]])
    gate = Gate.build("mahalanobis", view, 9.21, size_weight=16.0)  # σ_s = 0.25
    z, wh = np.array([[2.0, 0.0]]), np.array([[20.0 * np.e**0.25, 40.0 / np.e**0.5]])
    # Δᵀ S⁻¹ Δ = 4 / 4 (S = P̄ = 4 I); size term 16 (0.25² + 0.5²) = 5
    np.testing.assert_allclose(gate.matrix(z, wh), [[1.0 + 5.0]], rtol=1e-12)


@pytest.mark.parametrize("distance", [*QUADRATIC, "iou"])
def test_pairs_are_the_matrix_entries_inside_the_gate(distance: str) -> None:
    rng = np.random.default_rng(5)
    view = _view(rng, 60)
    z = view.xy[rng.integers(0, 60, 70)] + rng.normal(0, 4, (70, 2))
    wh = view.wh[rng.integers(0, 60, 70)] * rng.uniform(0.8, 1.2, (70, 2))
    threshold = {"euclidean": 100.0, "iou": 0.7}.get(distance, 9.21)
    gate = Gate.build(distance, view, threshold, size_weight=4.0 if distance != "iou" else 0.0)
    ti, dj, value = gate.pairs(z, wh)
    full = gate.matrix(z, wh)
    rt, rd = np.nonzero(full <= threshold)
    assert rt.size > 20
    np.testing.assert_array_equal(ti, rt)
    np.testing.assert_array_equal(dj, rd)
    np.testing.assert_allclose(value, full[rt, rd], rtol=1e-9)


def test_regions_are_the_covariances_the_gate_applies() -> None:
    rng = np.random.default_rng(6)
    view = _view(rng, 10)
    gate = Gate.build("coupled", view, 9.21)
    r = gate.regions(np.arange(10), np.arange(1, 11))
    np.testing.assert_allclose(r.shape, shapes("coupled", view.cov, view.S, view.velocity))
    assert r.r2 == 9.21 and len(r) == 10
    np.testing.assert_array_equal(r.take(np.array([2, 5])).track_id, [3, 6])
    # a point on the region's boundary along the first axis of C is at r² exactly
    c = r.shape[3]
    lam, vec = np.linalg.eigh(c)
    z = r.center[3] + np.sqrt(9.21 * lam[0]) * vec[:, 0]
    d = z - view.xy[3]
    assert d @ np.linalg.solve(c, d) == pytest.approx(9.21)


def test_warmup_centre_is_the_linear_extrapolation() -> None:
    """Paper 1's warm-up (SPEC §1.1 [R]): 2 y_k − y_{k−1} for consecutive frames, scaled by
    the frames elapsed, y_k after one association, the prediction once warmed up."""
    pxy = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]])
    hits = np.array([2, 1, 6])
    last = np.array([[10.0, 4.0], [5.0, 5.0], [1.0, 1.0]])
    prev = np.array([[8.0, 3.0], [5.0, 5.0], [0.0, 0.0]])
    last_k, prev_k = np.array([9, 9, 9]), np.array([8, 9, 8])
    c = warmup_centre(pxy, hits, last, prev, last_k, prev_k, k=11, warmup_hits=6)
    np.testing.assert_allclose(c, [[14.0, 6.0], [5.0, 5.0], [0.0, 0.0]])
