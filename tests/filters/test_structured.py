"""The structured Kalman filter of paper 3 (SPEC §3.2, X10 structural tests)."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from mvtrack.filters import kalman
from mvtrack.filters.base import Predictor
from mvtrack.filters.structured import (
    PartGraph,
    SKFParams,
    StructuredKalmanFilter,
    StructuredPredictor,
    inferred_measurements,
    init,
    predict,
    search_region,
    update,
)
from mvtrack.types import concat_rows, take_rows

FIG2_EDGES = [(0, 1), (1, 2), (0, 2), (2, 3)]  # relations 12, 23, 13, 34 of Fig. 2


def _filterpy_bank(
    params: SKFParams, z0: np.ndarray, r: float, relation: bool = False
) -> KalmanFilter:
    kf = KalmanFilter(dim_x=params.n, dim_z=2)
    kf.F, kf.H, kf.Q = params.F, params.H, params.Q_rel if relation else params.Q
    kf.R = r * np.eye(2)
    kf.P = params.P0(r)
    kf.x = np.zeros((params.n, 1))
    kf.x[:2, 0] = z0
    return kf


@pytest.mark.parametrize("model", ["ca", "cv"])
def test_alpha_zero_equals_independent_filterpy_kalman_filters(model: str) -> None:
    rng = np.random.default_rng(3)
    params = SKFParams(model=model)
    graph = PartGraph.from_edges(4, FIG2_EDGES)
    N, K, T = 3, 4, 40
    t = np.arange(T)[:, None, None, None]
    truth = rng.normal(0, 30, (1, N, K, 2)) + t * rng.normal(0, 2, (1, N, K, 2)) + 0.02 * t**2
    z = truth + rng.normal(0, 2, truth.shape)
    state = init(params, graph, z[0])
    cells = [[_filterpy_bank(params, z[0, n, k], 4.0) for k in range(K)] for n in range(N)]
    edges = graph.edges
    rels = [
        [_filterpy_bank(params, z[0, n, b] - z[0, n, a], 8.0, relation=True) for a, b in edges]
        for n in range(N)
    ]
    alpha = np.zeros((N, K))
    for k in range(1, T):
        state = predict(params, state)
        state, terms = update(params, graph, state, z[k], alpha)
        assert np.all(terms.neighbours == 0.0)
        for n in range(N):
            for p in range(K):
                cells[n][p].predict()
                cells[n][p].update(z[k, n, p])
                np.testing.assert_allclose(state.xc[n, p], cells[n][p].x[:, 0], atol=1e-9)
                np.testing.assert_allclose(state.Pc[n, p], cells[n][p].P, atol=1e-9)
            for e, (a, b) in enumerate(edges):
                rels[n][e].predict()
                rels[n][e].update(z[k, n, b] - z[k, n, a])
                np.testing.assert_allclose(state.xr[n, e], rels[n][e].x[:, 0], atol=1e-9)
                np.testing.assert_allclose(state.Pr[n, e], rels[n][e].P, atol=1e-9)


def test_fig2_topology_neighbour_counts_and_filters_of_region_1() -> None:
    graph = PartGraph.from_edges(4, FIG2_EDGES)
    assert dict(enumerate(graph.degree.tolist(), start=1)) == {1: 2, 2: 2, 3: 3, 4: 1}
    assert graph.filters_used_by(0) == ["KF1", "KF2", "KF3", "KF12", "KF13"]
    assert graph.neighbours(2) == [0, 1, 3]


def test_region_1_update_depends_on_exactly_kf1_kf2_kf3_kf12_kf13() -> None:
    """Perturb each filter (its prior state and, for cells, its measurement) in turn and see
    which ones move region 1's posterior."""
    rng = np.random.default_rng(0)
    params = SKFParams()
    graph = PartGraph.from_edges(4, FIG2_EDGES)
    z0 = rng.normal(0, 20, (1, 4, 2))
    state = predict(params, init(params, graph, z0))
    state.xc[..., 2:] = rng.normal(0, 1, state.xc[..., 2:].shape)
    state.xr[..., :2] += rng.normal(0, 1, state.xr[..., :2].shape)
    z = z0 + rng.normal(0, 2, z0.shape)
    alpha = np.array([[0.6, 0.3, 0.4, 0.2]])
    base, _ = update(params, graph, state, z, alpha)
    names = ["1", "2", "3", "4"]
    used = []
    for c in range(4):
        s = predict(params, init(params, graph, z0))
        s.xc[:], s.xr[:] = state.xc, state.xr
        s.xc[0, c, :2] += 3.0
        zz = z.copy()
        zz[0, c] += 3.0
        out, _ = update(params, graph, s, zz, alpha)
        if not np.allclose(out.xc[0, 0], base.xc[0, 0]):
            used.append(f"KF{names[c]}")
    for e, (a, b) in enumerate(graph.edges.tolist()):
        s = predict(params, init(params, graph, z0))
        s.xc[:], s.xr[:] = state.xc, state.xr
        s.xr[0, e, :2] += 3.0
        out, _ = update(params, graph, s, z, alpha)
        if not np.allclose(out.xc[0, 0], base.xc[0, 0]):
            used.append(f"KF{names[a]}{names[b]}")
    assert used == ["KF1", "KF2", "KF3", "KF12", "KF13"]


@pytest.mark.parametrize("pair", [(0, 1), (1, 0)])
def test_inferred_measurements_return_the_cell_centre_for_consistent_data(pair) -> None:
    graph = PartGraph.from_edges(2, [pair])
    assert graph.edges.tolist() == [[0, 1]]
    m = np.array([[[10.0, 100.0], [13.0, 131.0]]])
    head, tail = inferred_measurements(graph, m, (m[:, 1] - m[:, 0])[:, None])  # eq. (5)
    np.testing.assert_allclose(head[0, 0], m[0, 1])  # eq. (7): m~^j = m_c^i + m_r^ij
    np.testing.assert_allclose(tail[0, 0], m[0, 0])  # eq. (8): m~^i = m_c^j - m_r^ij


@pytest.mark.parametrize("hidden", [0, 1])
def test_hidden_part_with_exact_relation_is_updated_as_if_measured(hidden: int) -> None:
    """Both orientations: the occluded end is inferred by adding (head) or subtracting (tail)."""
    params = SKFParams()
    graph = PartGraph.chain(2)
    truth = np.array([[[50.0, 100.0], [53.0, 132.0]]])
    s = init(params, graph, truth)
    s = predict(params, s)
    s.xc[0, hidden, :2] += np.array([4.0, -3.0])  # the hidden part's prediction is off
    z = truth.copy()
    z[0, hidden] = np.nan
    alpha = np.zeros((1, 2))
    alpha[0, hidden] = 1.0
    out, terms = update(params, graph, s, z, alpha)
    want_x, want_P = kalman.update(
        s.xc[:, hidden], s.Pc[:, hidden], truth[:, hidden], params.H, params.R_cell
    )
    np.testing.assert_allclose(out.xc[:, hidden], want_x, atol=1e-12)
    np.testing.assert_allclose(out.Pc[:, hidden], want_P, atol=1e-12)
    assert np.all(terms.own[:, hidden] == 0.0)


def _turning_truth(T: int) -> np.ndarray:
    t = np.arange(T, dtype=float)
    centre = np.stack([160 + 80 * np.sin(t / 25.0), 120 + 60 * np.cos(t / 25.0)], axis=1)
    layout = np.array([[0.0, -21.0], [0.0, 0.0], [0.0, 32.0]])
    return centre[:, None, :] + layout[None]  # (T, 3, 2)


def test_vanished_part_stays_finite_and_follows_its_neighbours() -> None:
    rng = np.random.default_rng(5)
    params = SKFParams()
    skf = StructuredKalmanFilter(PartGraph.chain(3), params)
    T = 120
    truth = _turning_truth(T)
    z = truth + rng.normal(0, 1.0, truth.shape)
    s = skf.init(z[:1])
    coast = s.xc[:, 2].copy(), s.Pc[:, 2].copy()
    err_skf, err_coast = [], []
    for k in range(1, T):
        s = skf.predict(s)
        gone = k >= 30  # the legs vanish for 90 frames
        zk = z[k : k + 1].copy()
        alpha = np.zeros((1, 3))
        if gone:
            zk[0, 2] = np.nan
            alpha[0, 2] = 1.0
        cx, cP = coast
        cx, cP = cx @ params.F.T, params.F @ cP @ params.F.T + params.Q
        coast = kalman.update(cx, cP, zk[:, 2], params.H, params.R_cell)
        s, _ = skf.update(s, zk, alpha)
        assert np.all(np.isfinite(s.xc)) and np.all(np.isfinite(s.Pc))
        if gone:
            err_skf.append(np.linalg.norm(s.xc[0, 2, :2] - truth[k, 2]))
            err_coast.append(np.linalg.norm(coast[0][0, :2] - truth[k, 2]))
    assert max(err_skf) < 6.0
    assert max(err_coast) > 30.0
    eig = np.linalg.eigvalsh(s.Pc)
    assert np.all(eig > 0)


def test_lone_unmatched_part_coasts_with_growing_covariance() -> None:
    params = SKFParams()
    graph = PartGraph(1, np.zeros((0, 2), dtype=int))
    s = init(params, graph, np.array([[[0.0, 0.0]]]))
    before = s.Pc[0, 0, 0, 0]
    for _ in range(5):
        s = predict(params, s)
        s, _ = update(params, graph, s, np.full((1, 1, 2), np.nan), np.ones((1, 1)))
    assert s.Pc[0, 0, 0, 0] > before
    np.testing.assert_allclose(s.xc[0, 0], 0.0)


def test_new_part_appears_graph_grows_and_new_part_is_tracked() -> None:
    rng = np.random.default_rng(8)
    params = SKFParams()
    skf = StructuredKalmanFilter(PartGraph.chain(2), params)
    truth = _turning_truth(80)
    z = truth + rng.normal(0, 1.0, truth.shape)
    s = skf.init(z[:1, :2])
    for k in range(1, 20):
        s = skf.predict(s)
        s, _ = skf.update(s, z[k : k + 1, :2], np.zeros((1, 2)))
    skf, s = skf.add_part(s, z[20:21, 2], neighbours=[1])
    assert skf.graph.n_parts == 3 and skf.graph.edges.tolist() == [[0, 1], [1, 2]]
    assert skf.graph.degree.tolist() == [1, 2, 1]
    assert s.xc.shape == (1, 3, 6) and s.xr.shape == (1, 2, 6)
    np.testing.assert_allclose(s.xr[0, 1, :2], z[20, 2] - s.xc[0, 1, :2])
    for k in range(21, 80):
        s = skf.predict(s)
        s, _ = skf.update(s, z[k : k + 1], np.zeros((1, 3)))
    assert np.linalg.norm(s.xc[0, 2, :2] - truth[79, 2]) < 3.0
    assert np.linalg.norm(s.xr[0, 1, :2] - (truth[79, 2] - truth[79, 1])) < 3.0


def test_normalisation_options_differ_only_with_occluded_neighbours() -> None:
    graph = PartGraph.from_edges(3, [(0, 1), (1, 2)])
    z0 = np.array([[[0.0, 0.0], [0.0, 20.0], [0.0, 50.0]]])
    z = z0 + np.array([[[1.0, 1.0], [2.0, 2.0], [3.0, 1.0]]])
    outs = {}
    for norm in ("count", "weights"):
        params = SKFParams(normalise=norm)
        s = predict(params, init(params, graph, z0))
        outs[norm] = update(params, graph, s, z, np.array([[0.5, 1.0, 0.0]]))[0]
    # part 1 has neighbours with weights 0.5 and 1: 1/N = 1/2 vs 1/Σ(1-α) = 1/1.5
    t_count = outs["count"].xc[0, 1] - predict(SKFParams(), init(SKFParams(), graph, z0)).xc[0, 1]
    t_weights = (
        outs["weights"].xc[0, 1] - predict(SKFParams(), init(SKFParams(), graph, z0)).xc[0, 1]
    )
    np.testing.assert_allclose(t_weights, t_count * 2.0 / 1.5, atol=1e-12)
    # part 2 has one unoccluded neighbour... and α = 0: identical
    np.testing.assert_allclose(outs["count"].xc[0, 2], outs["weights"].xc[0, 2])


def test_search_region_is_the_scaled_mer_of_boxes_at_predicted_centres() -> None:
    centres = np.array([[[10.0, 10.0], [20.0, 30.0], [np.nan, np.nan]]])
    wh = np.array([[[4.0, 6.0], [10.0, 20.0], [5.0, 5.0]]])
    box = search_region(centres, wh, 1.5)
    # MER x: [8, 25], y: [7, 40] -> centre (16.5, 23.5), half sides 8.5*1.5, 16.5*1.5
    np.testing.assert_allclose(box[0], [16.5 - 12.75, 23.5 - 24.75, 16.5 + 12.75, 23.5 + 24.75])
    assert np.all(np.isnan(search_region(np.full((1, 2, 2), np.nan), np.ones((1, 2, 2)))))


def test_bad_inputs_raise_value_errors_naming_the_parameter() -> None:
    graph = PartGraph.chain(3)
    params = SKFParams()
    s = init(params, graph, np.zeros((2, 3, 2)))
    with pytest.raises(ValueError, match="alpha"):
        update(params, graph, s, np.zeros((2, 3, 2)), np.full((2, 3), 1.5))
    with pytest.raises(ValueError, match="z must have shape"):
        update(params, graph, s, np.zeros((2, 2, 2)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="model"):
        SKFParams(model="ukf")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="edges"):
        PartGraph(3, np.array([[1, 0]]))
    with pytest.raises(ValueError, match="itself"):
        PartGraph.from_edges(3, [(1, 1)])


def test_structured_predictor_follows_the_predictor_protocol() -> None:
    """Whole-object updates move the rigid layout: the mean of the parts is then exactly one CA
    Kalman filter (filterpy) on the object measurements, coasting where the mask is False."""
    pred = StructuredPredictor()
    assert isinstance(pred, Predictor) and pred.name == "structured"
    rng = np.random.default_rng(2)
    T = 40
    truth = np.stack([100 + 2.0 * np.arange(T), 80 + 1.0 * np.arange(T)], axis=1)
    z = truth + rng.normal(0, 1, truth.shape)
    s = concat_rows(pred.init(z[:1]), pred.init(np.array([[300.0, 300.0]])))
    ref = _filterpy_bank(pred.params, z[0], 4.0)
    for k in range(1, T):
        s = pred.predict(s)
        ref.predict()
        np.testing.assert_allclose(pred.position(s)[0], ref.x[:2, 0], atol=1e-9)
        np.testing.assert_allclose(pred.position_cov(s)[0], ref.P[:2, :2] / 3.0, atol=1e-9)
        zk = np.stack([z[k], [300.0, 300.0]])
        s = pred.update(s, zk, np.array([k < 30, True]))
        if k < 30:
            ref.update(z[k])
        np.testing.assert_allclose(pred.velocity(s)[0], ref.x[2:4, 0], atol=1e-9)
    one = take_rows(s, np.array([1]))
    np.testing.assert_allclose(pred.position(one)[0], [300.0, 300.0], atol=1e-9)
    cov = pred.position_cov(s)
    assert cov[0, 0, 0] > 2 * cov[1, 0, 0]  # the first track coasted for 10 frames
    np.testing.assert_allclose(
        pred.innovation_cov(s) - cov, np.broadcast_to(4.0 / 3 * np.eye(2), (2, 2, 2))
    )


def test_occlusion_scaled_relation_noise_keeps_the_learned_offset() -> None:
    graph = PartGraph.chain(2)
    z0 = np.array([[[0.0, 0.0], [0.0, 30.0]]])
    z = np.array([[[0.0, 0.0], [6.0, 30.0]]])  # part 1 seems to jump (a biased centroid)
    out = {}
    for noise in ("constant", "occlusion"):
        params = SKFParams(relation_noise=noise)
        s = predict(params, init(params, graph, z0))
        out[noise, 0.0] = update(params, graph, s, z, np.zeros((1, 2)))[0]
        out[noise, 0.9] = update(params, graph, s, z, np.array([[0.0, 0.9]]))[0]
    # with α = 0 both settings are the same standard update
    np.testing.assert_allclose(out["constant", 0.0].xr, out["occlusion", 0.0].xr)
    # with α^j = 0.9, the relation measurement (15) is pulled by j's prediction in both,
    # but the scaled noise (R_r / 0.1) lets the offset move much less
    move_c = np.abs(out["constant", 0.9].xr[0, 0, 0])
    move_o = np.abs(out["occlusion", 0.9].xr[0, 0, 0])
    assert 0 < move_o < 0.5 * move_c


def test_alpha_zero_equals_the_batched_kalman_functions() -> None:
    rng = np.random.default_rng(11)
    params = SKFParams()
    graph = PartGraph.chain(3)
    N, K, T = 5, 3, 25
    z = np.cumsum(rng.normal(0, 2, (T, N, K, 2)), axis=0) + 100
    state = init(params, graph, z[0])
    x, P = state.xc.reshape(N * K, -1).copy(), state.Pc.reshape(N * K, 6, 6).copy()
    for k in range(1, T):
        state = predict(params, state)
        x, P = kalman.predict(x, P, params.F, params.Q)
        state, _ = update(params, graph, state, z[k], np.zeros((N, K)))
        x, P = kalman.update(x, P, z[k].reshape(N * K, 2), params.H, params.R_cell)
    np.testing.assert_allclose(state.xc.reshape(N * K, -1), x, atol=1e-9)
    np.testing.assert_allclose(state.Pc.reshape(N * K, 6, 6), P, atol=1e-9)


def test_make_predictor_builds_the_structured_predictor() -> None:
    from mvtrack.filters.predictors import make_predictor

    pred = make_predictor("structured", r=9.0)
    assert isinstance(pred, StructuredPredictor) and pred.params.r_cell == 9.0
    s = pred.predict(pred.init(np.array([[10.0, 20.0], [50.0, 60.0]])))
    np.testing.assert_allclose(pred.position(s), [[10.0, 20.0], [50.0, 60.0]])
    box = pred.search_region(pred.init_parts(np.zeros((1, 3, 2)), wh=np.ones((1, 3, 2))))
    np.testing.assert_allclose(box, [[-0.75, -0.75, 0.75, 0.75]])


def test_batch_of_objects_equals_one_object_at_a_time() -> None:
    rng = np.random.default_rng(21)
    params = SKFParams(normalise="weights")
    graph = PartGraph.from_edges(4, FIG2_EDGES)
    N, T = 6, 15
    z = np.cumsum(rng.normal(0, 2, (T, N, 4, 2)), axis=0)
    alpha = rng.uniform(0, 1, (T, N, 4))
    z[rng.random((T, N, 4)) < 0.15] = np.nan  # some parts unmatched
    z[0] = np.nan_to_num(z[0])
    batch = init(params, graph, z[0])
    singles = [init(params, graph, z[0, n : n + 1]) for n in range(N)]
    for k in range(1, T):
        batch, _ = update(params, graph, predict(params, batch), z[k], alpha[k])
        singles = [
            update(params, graph, predict(params, s), z[k, n : n + 1], alpha[k, n : n + 1])[0]
            for n, s in enumerate(singles)
        ]
    for n, s in enumerate(singles):
        np.testing.assert_allclose(batch.xc[n], s.xc[0], atol=1e-12)
        np.testing.assert_allclose(batch.Pr[n], s.Pr[0], atol=1e-12)


def test_covariances_stay_symmetric_positive_definite_under_random_occlusion() -> None:
    rng = np.random.default_rng(4)
    params = SKFParams()
    graph = PartGraph.chain(3)
    s = init(params, graph, rng.normal(0, 10, (20, 3, 2)))
    for _ in range(200):
        z = rng.normal(0, 10, (20, 3, 2))
        z[rng.random((20, 3)) < 0.3] = np.nan
        s, _ = update(params, graph, predict(params, s), z, rng.uniform(0, 1, (20, 3)))
    for P in (s.Pc, s.Pr):
        np.testing.assert_allclose(P, np.swapaxes(P, -1, -2), atol=1e-9)
        assert np.linalg.eigvalsh(P).min() > 0
    assert np.all(np.isfinite(s.xc)) and np.all(np.isfinite(s.xr))


def test_tracker_runs_with_the_structured_predictor() -> None:
    from mvtrack.tracking import TrackerConfig, track_detections
    from mvtrack.types import Detections

    rng = np.random.default_rng(0)
    truth = {
        k: np.array([[100 + 2.0 * k, 100.0 + k], [300 - 2.0 * k, 220.0 + k]]) for k in range(40)
    }
    frames = [
        Detections.from_tlwh(
            k,
            np.hstack([truth[k] + rng.normal(0, 1, (2, 2)) - [10, 20], np.tile([20, 40], (2, 1))]),
            np.ones(2),
        )
        for k in range(40)
    ]
    rows = np.asarray(track_detections(frames, TrackerConfig(predictor="structured")).to_mot())
    ids = np.unique(rows[:, 1])
    assert len(ids) == 2
    for i in ids:  # each track stays on one target: its centres are near one truth path
        r = rows[rows[:, 1] == i]
        k = r[:, 0].astype(int) - 1  # MOTChallenge frames are 1-based
        centre = r[:, 2:4] + r[:, 4:6] / 2
        d = np.array(
            [
                [np.linalg.norm(c - truth[kk][t]) for t in (0, 1)]
                for c, kk in zip(centre, k, strict=True)
            ]
        )
        assert np.all(d.min(axis=1) < 3.0) and len(set(d.argmin(axis=1).tolist())) == 1


def test_relation_derivatives_are_damped_by_the_occlusion_of_their_ends() -> None:
    graph = PartGraph.chain(3)  # relations (1, 2) and (2, 3)
    z0 = np.array([[[0.0, 0.0], [0.0, 20.0], [0.0, 50.0]]])
    z = np.array([[[2.0, 0.0], [2.0, 20.0], [4.0, 50.0]]])
    p = SKFParams()
    s = predict(p, init(p, graph, z0))
    alpha = np.array([[0.0, 0.2, 0.7]])
    plain = update(SKFParams(damping_by="unmatched"), graph, s, z, alpha)[0]
    damped = update(p, graph, s, z, alpha)[0]
    np.testing.assert_allclose(damped.xr[..., :2], plain.xr[..., :2])  # offsets as (14) gives
    d = p.relation_damping
    np.testing.assert_allclose(damped.xr[0, 0, 2:], plain.xr[0, 0, 2:] * d**0.2)
    np.testing.assert_allclose(damped.xr[0, 1, 2:], plain.xr[0, 1, 2:] * d**0.7)
    # α = 0 everywhere: no damping (the SKF stays a set of independent KFs, X10)
    none = update(p, graph, s, z, np.zeros((1, 3)))[0]
    ref = update(SKFParams(damping_by="unmatched"), graph, s, z, np.zeros((1, 3)))[0]
    np.testing.assert_allclose(none.xr, ref.xr)
    # an unmatched end: the relation coasts and is damped by d, whichever reading
    z_gone = z.copy()
    z_gone[0, 2] = np.nan
    a = update(p, graph, s, z_gone, alpha)[0]
    b = update(SKFParams(damping_by="unmatched"), graph, s, z_gone, alpha)[0]
    np.testing.assert_allclose(a.xr[0, 1], b.xr[0, 1])
    np.testing.assert_allclose(a.xr[0, 1, 2:], s.xr[0, 1, 2:] * d)
    with pytest.raises(ValueError, match="damping_by"):
        SKFParams(damping_by="always")  # type: ignore[arg-type]


def test_update_order_matters_only_under_occlusion() -> None:
    from mvtrack.filters.structured import relation_measurement

    graph = PartGraph.chain(3)
    z0 = np.array([[[0.0, 0.0], [0.0, 20.0], [0.0, 50.0]]])
    z = np.array([[[2.0, 0.0], [2.0, 20.0], [4.0, 50.0]]])
    first = SKFParams()
    cells = SKFParams(order="cells-first")
    s = predict(first, init(first, graph, z0))
    # without occlusion (15) blends measurements only: both orders give the same filters
    a = update(first, graph, s, z, np.zeros((1, 3)))[0]
    b = update(cells, graph, s, z, np.zeros((1, 3)))[0]
    np.testing.assert_allclose(a.xr, b.xr)
    np.testing.assert_allclose(a.xc, b.xc)
    alpha = np.array([[0.0, 0.0, 0.7]])
    a, ta = update(first, graph, s, z, alpha)
    b, tb = update(cells, graph, s, z, alpha)
    np.testing.assert_allclose(a.xc, b.xc)  # (13) reads priors only
    # the relation measurement of (15): the cells' priors, or their posteriors
    np.testing.assert_allclose(ta.relation_z, relation_measurement(graph, z, alpha, s.xc[..., :2]))
    np.testing.assert_allclose(tb.relation_z, relation_measurement(graph, z, alpha, b.xc[..., :2]))
    assert not np.allclose(ta.relation_z[0, 1], tb.relation_z[0, 1])
    K = kalman.gain(s.Pr, first.H, first.R_rel)
    expect = s.xr[0, 1] + K[0, 1] @ (tb.relation_z[0, 1] - s.xr[0, 1, :2])
    expect[2:] *= cells.relation_damping ** 0.7  # its derivatives damped by d ** α (α³ = 0.7)
    np.testing.assert_allclose(b.xr[0, 1], expect)  # eq. (14) with that measurement
    with pytest.raises(ValueError, match="order"):
        SKFParams(order="sideways")  # type: ignore[arg-type]
