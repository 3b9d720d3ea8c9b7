"""Spatially pre-gated candidate pairs equal the dense computation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.association.distances import DISTANCES, TrackView, distance_matrix
from mvtrack.association.gating import candidate_pairs, gate_mask
from mvtrack.types import Detections


def _scene(seed: int, n: int = 300, m: int = 320) -> tuple[TrackView, Detections]:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 800, (n, 2))
    cov = np.zeros((n, 2, 2))
    cov[:, 0, 0] = rng.uniform(1, 10, n)
    cov[:, 1, 1] = rng.uniform(1, 10, n)
    cov[:5] *= 50.0  # a few very uncertain (long-coasting) tracks: the "wide" query path
    a = rng.normal(size=(n, 2, 2))
    s = cov + a @ a.transpose(0, 2, 1)
    view = TrackView(xy, cov, s, rng.normal(0, 3, (n, 2)), rng.uniform(20, 40, (n, 2)))
    real = min(n, m - m // 10)
    z = np.vstack([xy[:real] + rng.normal(0, 3, (real, 2)), rng.uniform(0, 800, (m - real, 2))])
    return view, Detections(0, z, rng.uniform(20, 40, (m, 2)))


@pytest.mark.parametrize("name", list(DISTANCES))
def test_grid_pairs_equal_dense_pairs(name: str) -> None:
    view, dets = _scene(7)
    ti, dj, c = candidate_pairs(view, dets, name, method="grid")
    td, dd, cd = candidate_pairs(view, dets, name, method="dense")
    assert ti.size > 100
    np.testing.assert_array_equal(ti, td)
    np.testing.assert_array_equal(dj, dd)
    np.testing.assert_array_equal(c, cd)


def test_pairs_match_the_gate_on_the_dense_matrix() -> None:
    view, dets = _scene(8)
    for gate in (25.0, 400.0, 2500.0):
        ti, dj, c = candidate_pairs(view, dets, "euclidean", gate, method="grid")
        d = distance_matrix("euclidean", view, dets)
        expected = np.argwhere(d <= gate)
        np.testing.assert_array_equal(np.stack([ti, dj], axis=1), expected)
        np.testing.assert_allclose(c, d[ti, dj])


def test_gate_is_inclusive_and_params_are_passed() -> None:
    view = TrackView.from_arrays([[0.0, 0.0]], cov=1.0, velocity=[[1.0, 0.0]])
    z = np.array([[3.0, 0.0], [0.0, 3.0]])
    _, dj, _ = candidate_pairs(view, z, "euclidean", 9.0)
    assert dj.tolist() == [0, 1]
    # coupled ρ = 2: along-track 9/4 passes a gate of 3, cross-track 9 does not
    _, dj, c = candidate_pairs(view, z, "coupled", 3.0, rho=2.0)
    assert dj.tolist() == [0] and c[0] == pytest.approx(2.25)
    _, dj, c = candidate_pairs(view, z, "coupled", 3.0, rho=1.0)
    assert dj.size == 0


def test_empty_inputs() -> None:
    view, dets = _scene(9, 10, 10)
    for method in ("dense", "grid"):
        ti, dj, c = candidate_pairs(view, np.zeros((0, 2)), "euclidean", method=method)
        assert ti.size == dj.size == c.size == 0
        empty = TrackView.from_arrays(np.zeros((0, 2)))
        ti, dj, c = candidate_pairs(empty, dets, "mahalanobis", method=method)
        assert ti.size == 0
    assert gate_mask(view, dets, "euclidean").shape == (10, 10)


def test_unknown_method_raises() -> None:
    view, dets = _scene(9, 3, 3)
    with pytest.raises(ValueError, match="unknown method"):
        candidate_pairs(view, dets, "euclidean", method="octree")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="NaN"):
        candidate_pairs(view, np.array([[np.nan, 1.0]]), "euclidean")


def test_grid_handles_far_tracks_negative_coordinates_and_tiny_gates() -> None:
    rng = np.random.default_rng(10)
    xy = np.vstack([rng.uniform(-5000, 5000, (200, 2)), [[1e6, -1e6]]])
    view = TrackView.from_arrays(xy, cov=2.0)
    z = np.vstack([xy[:150] + rng.normal(0, 1, (150, 2)), rng.uniform(-6000, 6000, (50, 2))])
    for gate in (1e-6, 1.0, 9.21, 1e4):
        got = candidate_pairs(view, z, "mahalanobis", gate, method="grid")
        ref = candidate_pairs(view, z, "mahalanobis", gate, method="dense")
        for a, b in zip(got, ref, strict=True):
            np.testing.assert_array_equal(a, b)


@settings(max_examples=25, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 120),
    st.integers(1, 120),
    st.floats(1.0, 1e4),
    st.sampled_from(["euclidean", "mahalanobis", "coupled", "iou"]),
)
def test_grid_equals_dense_on_random_scenes(
    seed: int, n: int, m: int, scale: float, name: str
) -> None:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, scale, (n, 2))
    xy[: n // 4] = xy[0]  # some tracks on top of each other
    cov = rng.uniform(0.1, 50, n)[:, None, None] * np.eye(2)
    view = TrackView(xy, cov, cov + np.eye(2), rng.normal(0, 2, (n, 2)), rng.uniform(1, 50, (n, 2)))
    z = np.vstack([xy[rng.integers(0, n, m)] + rng.normal(0, 5, (m, 2))])
    dets = Detections(0, z, rng.uniform(1, 50, (m, 2)))
    got = candidate_pairs(view, dets, name, method="grid")
    ref = candidate_pairs(view, dets, name, method="dense")
    for a, b in zip(got, ref, strict=True):
        np.testing.assert_array_equal(a, b)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["nearest", "greedy", "optimal"]))
def test_gate_and_assign_invariant_under_shuffled_detections(seed: int, rule: str) -> None:
    """Shuffling the detection rows of a crowded frame changes nothing but the row numbers."""
    from mvtrack.association import assign

    rng = np.random.default_rng(seed)
    n, m = 150, 160
    xy = rng.uniform(0, 300, (n, 2))
    view = TrackView.from_arrays(xy, cov=4.0, velocity=rng.normal(0, 2, (n, 2)))
    z = np.vstack([xy[:140] + rng.normal(0, 3, (140, 2)), rng.uniform(0, 300, (m - 140, 2))])
    perm = rng.permutation(m)
    results = []
    for order in (np.arange(m), perm):
        ti, dj, c = candidate_pairs(view, z[order], "coupled", method="grid")
        a = assign(ti, dj, c, n, m, rule)  # type: ignore[arg-type]
        results.append((a.track, order[a.det], np.sort(order[a.unmatched_dets])))
    for x, y in zip(*results, strict=True):
        np.testing.assert_array_equal(x, y)
