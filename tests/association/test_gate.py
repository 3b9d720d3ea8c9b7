"""The gate: its quadratic forms are the distances of papers 1 and 2, its pairs are the pairs
inside it, its regions are the ones it applies, and paper 1's warm-up centre by hand."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association.distances import distance_matrix
from mvtrack.association.gate import (
    QUADRATIC,
    Gate,
    euclidean_box_variance,
    shapes,
    tracker_gate,
    warmup_centre,
)
from mvtrack.association.view import TrackView
from mvtrack.registry import CHI2_2DOF_99
from mvtrack.tracking import Tracker, TrackerConfig, paper1
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


# ------------------------------------------------------------- the Euclidean gate in box sizes


def test_the_euclidean_gate_in_box_sizes_is_the_distance_over_each_box() -> None:
    """``C = s² diag(w², h²)``: the value is ``((Δx / w)² + (Δy / h)²) / s²``, by hand."""
    rng = np.random.default_rng(8)
    view = _view(rng, 30)
    z = view.xy[rng.integers(0, 30, 40)] + rng.normal(0, 6, (40, 2))
    wh = rng.uniform(10, 60, (40, 2))
    gate = Gate.build("euclidean", view, CHI2_2DOF_99, box_var=0.03)
    d = z[None, :, :] - view.xy[:, None, :]
    by_hand = ((d[..., 0] / view.wh[:, None, 0]) ** 2
               + (d[..., 1] / view.wh[:, None, 1]) ** 2) / 0.03
    np.testing.assert_allclose(gate.matrix(z, wh), by_hand, rtol=1e-12)
    ti, dj, value = gate.pairs(z, wh)
    rt, rd = np.nonzero(by_hand <= CHI2_2DOF_99)
    assert rt.size > 20
    np.testing.assert_array_equal(ti, rt)
    np.testing.assert_array_equal(dj, rd)
    np.testing.assert_allclose(value, by_hand[rt, rd], rtol=1e-12)
    # without box_var it is eq. (8) in pixels
    np.testing.assert_allclose(Gate.build("euclidean", view, 100.0).matrix(z, wh),
                               (d**2).sum(axis=-1), rtol=1e-12)


@pytest.mark.parametrize("fps", [5.0, 25.0, 60.0])
def test_the_box_variance_is_the_first_innovation_of_a_new_track(fps: float) -> None:
    """``s²`` is what the size-scaled constant-velocity filter gives a new track one frame
    after its first detection: ``S / diag(w², h²)`` of the tracker's own gate."""
    config = TrackerConfig(predictor="kalman-cv", fps=fps)
    tracker = Tracker(config)
    wh = np.array([[40.0, 100.0]])
    tracker.step(Detections(0, [[300.0, 200.0]], wh))
    S = tracker.gates().shape[0]
    s2 = euclidean_box_variance(config.measurement_noise, config.velocity_prior,
                                config.accel_noise, fps)
    np.testing.assert_allclose(np.diag(S) / wh[0] ** 2, [s2, s2], rtol=1e-12)
    assert S[0, 1] == 0.0
    if fps == 25.0:
        assert np.sqrt(CHI2_2DOF_99 * s2) == pytest.approx(0.466, abs=1e-3)  # box sizes


def test_tracker_gate_explicit_gates_keep_their_units() -> None:
    noise = (0.1, 1.5, 1.0, 25.0)
    assert tracker_gate("euclidean", 400.0, *noise) == (400.0, 0.0)  # px², a 20 px circle
    g, s2 = tracker_gate("euclidean", None, *noise)
    assert g == CHI2_2DOF_99 and s2 == pytest.approx(0.02 + 0.06**2 + 0.25 * 0.0016**2)
    assert tracker_gate("mahalanobis", None, *noise) == (CHI2_2DOF_99, 0.0)
    assert tracker_gate("iou", None, *noise) == (0.7, 0.0)
    assert tracker_gate("coupled", 5.99, *noise) == (5.99, 0.0)


def test_an_explicit_euclidean_gate_is_a_circle_in_pixels_for_any_box() -> None:
    """Paper 1's preset and ``gate=400``: the circle of 20 px whatever the box's size."""
    for config in (paper1(fps=25.0), TrackerConfig(distance="euclidean", gate=400.0)):
        tracker = Tracker(config)
        tracker.step(Detections(0, [[100.0, 100.0], [500.0, 300.0]],
                                [[10.0, 20.0], [300.0, 400.0]]))
        regions = tracker.gates()
        assert regions.r2 == 400.0
        np.testing.assert_array_equal(regions.shape, np.broadcast_to(np.eye(2), (2, 2, 2)))


def _walkers(scale: float, fps: float, seconds: float, speed: float, seed: int
             ) -> list[Detections]:
    """Three people (30 × 80 px boxes times ``scale``) walking side by side at ``speed``
    box widths per second, their boxes jittered by 5 % of their size, one in ten missed."""
    rng = np.random.default_rng(seed)
    start = np.array([[100.0, 200.0], [160.0, 230.0], [220.0, 190.0]]) * scale
    wh = np.array([30.0, 80.0]) * scale
    frames = []
    for k in range(int(seconds * fps)):
        xy = start + np.array([speed * wh[0] * k / fps, 0.0])
        xy = xy + rng.normal(0, 0.05, xy.shape) * wh
        seen = rng.random(3) >= 0.1
        frames.append(Detections(k, xy[seen], np.tile(wh, (int(seen.sum()), 1))))
    return frames


def _run(config: TrackerConfig, frames: list[Detections], box_var: float | None = None
         ) -> list[tuple[list, list]]:
    tracker = Tracker(config)
    if box_var is not None:  # the counterfactual: another gate in box sizes
        tracker._box_var = box_var
    out = []
    for d in frames:
        f = tracker.step(d)
        out.append((f.track_id.tolist(), f.det_index.tolist()))
    return out


def test_the_default_euclidean_gate_means_the_same_in_any_image() -> None:
    """A scene and the same scene 4 times larger (a 640×480 video and a 2560×1920 one: the
    factor is exact in floating point): the same associations, frame by frame. The pixel gate
    of 100 px² does not carry over."""
    small, large = _walkers(1.0, 25.0, 4.0, 1.0, 0), _walkers(4.0, 25.0, 4.0, 1.0, 0)
    config = TrackerConfig(predictor="kalman-cv", distance="euclidean", fps=25.0)
    ref = _run(config, small)
    assert ref == _run(config, large)
    assert max(max(ids, default=0) for ids, _ in ref) == 3  # three people, three IDs
    pixels = config.replace(gate=100.0)
    assert _run(pixels, small) != _run(pixels, large)


@pytest.mark.parametrize("fps", [5.0, 10.0, 30.0])
def test_the_default_euclidean_gate_follows_a_new_object_at_any_frame_rate(fps: float
                                                                             ) -> None:
    """People walking 3 box widths per second (0.6 of a width per frame at 5 fps): each keeps
    one ID through 4 s at any frame rate. A gate of the size of the one at 30 fps
    (0.46 box sizes) loses them at 5 fps: a new track's first step is its whole motion."""
    frames = _walkers(1.0, fps, 4.0, 3.0, 1)
    config = TrackerConfig(predictor="kalman-cv", distance="euclidean", fps=fps)
    rows = _run(config, frames)
    ids = {i for f, _ in rows for i in f}
    assert ids == {1, 2, 3}
    assert sum(len(f) for f, _ in rows) >= 0.85 * 3 * len(frames)
    if fps == 5.0:  # the gate of 30 fps at 5 fps: new tracks die at their second frame
        s2_30 = euclidean_box_variance(0.1, 1.5, 1.0, 30.0)
        rows = _run(config, frames, box_var=s2_30)
        assert sum(len(f) for f, _ in rows) < 0.5 * 3 * len(frames)
