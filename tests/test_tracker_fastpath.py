"""The tracker's fast paths equal the general code they replace.

- ``kalman-cv`` (:class:`mvtrack.filters.cv.KalmanCVPredictor`, the closed-form per-axis CV
  Kalman filter) against the general per-axis Kalman filter of
  :mod:`mvtrack.filters.predictors` on the same model.
- :mod:`mvtrack.association.discs` against :mod:`mvtrack.association` (gating values and the
  penalised optimal assignment), and against brute force on tiny problems.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mvtrack.association import TrackView, assign, candidate_pairs
from mvtrack.association import discs as fa
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


def _scene(rng, n, m, spread):
    txy = rng.uniform(0, spread, (n, 2))
    dxy = np.vstack([txy[: m // 2] + rng.normal(0, 3, (m // 2, 2)),
                     rng.uniform(0, spread, (m - m // 2, 2))])
    return txy, dxy


@pytest.mark.parametrize(
    "n, m, spread", [(8, 9, 80.0), (100, 103, 400.0), (300, 280, 700.0), (2000, 1900, 1500.0)]
)
@pytest.mark.parametrize("metric", ["euclidean", "mahalanobis"])
def test_gate_pairs_equal_association_candidate_pairs(n, m, spread, metric) -> None:
    rng = np.random.default_rng(n)
    txy, dxy = _scene(rng, n, m, spread)
    s = rng.uniform(2.0, 30.0, n)
    s[:3] = 400.0  # a few wide gates (long coasting)
    scale = s if metric == "mahalanobis" else None
    gate = 9.21 if metric == "mahalanobis" else 100.0
    ti, dj, cost = fa.gate_pairs(txy, dxy, scale, gate)
    view = TrackView.from_arrays(txy, cov=None, S=s[:, None, None] * np.eye(2))
    rt, rd, rc = candidate_pairs(view, dxy, metric, gate)
    got = dict(zip(zip(ti.tolist(), dj.tolist(), strict=True), cost.tolist(), strict=True))
    want = dict(zip(zip(rt.tolist(), rd.tolist(), strict=True), rc.tolist(), strict=True))
    assert got.keys() == want.keys() and len(got) > 0
    np.testing.assert_allclose([got[k] for k in want], list(want.values()), rtol=1e-12)


def _brute(ti, dj, cost, n, m, half_u):
    """Minimum of Σ cost + half_u · unmatched over every matching (tiny problems)."""
    best, best_set = np.inf, None
    pairs = list(range(len(ti)))
    for r in range(min(n, m) + 1):
        for sub in itertools.combinations(pairs, r):
            if len({ti[p] for p in sub}) < r or len({dj[p] for p in sub}) < r:
                continue
            total = sum(cost[p] for p in sub) + half_u * (n + m - 2 * r)
            if total < best - 1e-12:
                best, best_set = total, {(ti[p], dj[p]) for p in sub}
    return best_set


def test_optimal_equals_brute_force_on_tiny_problems() -> None:
    rng = np.random.default_rng(1)
    for _ in range(60):
        n, m = rng.integers(1, 5), rng.integers(1, 5)
        allowed = rng.random((n, m)) < 0.6
        ti, dj = np.nonzero(allowed)
        cost = rng.uniform(0, 1, ti.size)
        got = fa.optimal(ti, dj, cost, n, m, 0.5)
        assert set(zip(got[0].tolist(), got[1].tolist(), strict=True)) == _brute(
            ti, dj, cost, n, m, 0.5
        )


@pytest.mark.parametrize("n, m, spread", [(40, 45, 150.0), (800, 760, 900.0), (3000, 2900, 1200.0)])
def test_optimal_equals_association_assign_with_the_same_penalty(n, m, spread) -> None:
    rng = np.random.default_rng(n + 1)
    txy, dxy = _scene(rng, n, m, spread)
    gate = 400.0
    ti, dj, cost = fa.gate_pairs(txy, dxy, None, gate)
    mt, md = fa.optimal(ti, dj, cost, n, m, gate)
    ref = assign(ti, dj, cost, n, m, "optimal", unmatched_cost=2 * gate)
    assert set(zip(mt.tolist(), md.tolist(), strict=True)) == set(
        zip(ref.track.tolist(), ref.det.tolist(), strict=True)
    )
    if n * m <= 2500:  # the single dense solve gives the same matching
        dt, dd = fa.dense_optimal(txy, dxy, None, gate)
        assert set(zip(dt.tolist(), dd.tolist(), strict=True)) == set(
            zip(mt.tolist(), md.tolist(), strict=True)
        )


def test_optimal_is_invariant_to_permuting_detections() -> None:
    rng = np.random.default_rng(9)
    txy, dxy = _scene(rng, 500, 480, 600.0)
    perm = rng.permutation(480)
    a = fa.optimal(*fa.gate_pairs(txy, dxy, None, 225.0), 500, 480, 225.0)
    b = fa.optimal(*fa.gate_pairs(txy, dxy[perm], None, 225.0), 500, 480, 225.0)
    assert set(zip(a[0].tolist(), a[1].tolist(), strict=True)) == set(
        zip(b[0].tolist(), perm[b[1]].tolist(), strict=True)
    )


@pytest.mark.parametrize("stretch, sized", [(False, False), (True, False), (True, True)])
def test_dense_two_stage_equals_two_sparse_stages(stretch: bool, sized: bool) -> None:
    rng = np.random.default_rng(4)
    for _ in range(20):
        txy, dxy = _scene(rng, 30, 33, 120.0)
        f2 = rng.uniform(1.0, 6.0, (30, 2)) if stretch else None  # per-axis box factors²
        twh, dwh = rng.uniform(10, 60, (30, 2)), rng.uniform(10, 60, (33, 2))
        size = (twh, dwh, 0.5) if sized else None
        mt, md, ud = fa.dense_two_stage(txy, dxy, f2, 25.0, 144.0, f2, size)
        t1, d1 = fa.optimal(*fa.gate_pairs(txy, dxy, f2, 25.0, size), 30, 33, 25.0)
        lt = np.setdiff1d(np.arange(30), t1)
        ld = np.setdiff1d(np.arange(33), d1)
        size2 = (twh[lt], dwh[ld], 0.5) if sized else None
        t2, d2 = fa.optimal(
            *fa.gate_pairs(txy[lt], dxy[ld], None if f2 is None else f2[lt], 144.0, size2),
            lt.size, ld.size, 144.0,
        )
        want = set(zip(t1.tolist(), d1.tolist(), strict=True)) | set(
            zip(lt[t2].tolist(), ld[d2].tolist(), strict=True)
        )
        assert set(zip(mt.tolist(), md.tolist(), strict=True)) == want
        np.testing.assert_array_equal(ud, np.setdiff1d(np.arange(33), md))


@pytest.mark.parametrize("n, m, spread", [(7, 9, 60.0), (100, 95, 300.0), (900, 880, 1200.0)])
def test_gate_pairs_with_per_axis_factors_equal_a_hand_computed_ellipse(n, m, spread) -> None:
    rng = np.random.default_rng(n + 7)
    txy, dxy = _scene(rng, n, m, spread)
    f2 = rng.uniform(1.0, 9.0, (n, 2))  # (f_x², f_y²)
    ti, dj, cost = fa.gate_pairs(txy, dxy, f2, 100.0)
    d = dxy[None, :, :] - txy[:, None, :]
    want = d[..., 0] ** 2 / f2[:, 0, None] + d[..., 1] ** 2 / f2[:, 1, None]
    wt, wd = np.nonzero(want <= 100.0)
    assert wt.size > 0
    got = dict(zip(zip(ti.tolist(), dj.tolist(), strict=True), cost.tolist(), strict=True))
    assert got.keys() == set(zip(wt.tolist(), wd.tolist(), strict=True))
    np.testing.assert_allclose([got[k] for k in zip(wt, wd, strict=True)], want[wt, wd])


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


@pytest.mark.parametrize("n, m", [(6, 7), (100, 97), (900, 880)])
def test_gate_pairs_size_term_is_the_capped_weighted_size_difference(n, m) -> None:
    rng = np.random.default_rng(n)
    txy, dxy = _scene(rng, n, m, 12.0 * np.sqrt(n))
    f2 = rng.uniform(1.0, 4.0, (n, 2))
    twh, dwh = rng.uniform(10, 60, (n, 2)), rng.uniform(10, 60, (m, 2))
    ti, dj, plain = fa.gate_pairs(txy, dxy, f2, 100.0)
    si, sj, sized = fa.gate_pairs(txy, dxy, f2, 100.0, (twh, dwh, 0.3))
    np.testing.assert_array_equal(ti, si)  # the gate is on the position only
    np.testing.assert_array_equal(dj, sj)
    assert ti.size > 0
    d = dwh[dj] - twh[ti]
    s = d[:, 0] ** 2 / f2[ti, 0] + d[:, 1] ** 2 / f2[ti, 1]
    np.testing.assert_allclose(sized, plain + 0.3 * np.minimum(s, 100.0))
    assert (sized < 200.0).all()  # below leaving both unmatched (u = 2 gate)


def _cluttered_frames(n: int, frames: int, seed: int) -> list:
    """Targets moving at constant velocity with missed detections and false alarms (rows
    shuffled): every frame has births, and most have deletions."""
    from mvtrack.types import Detections

    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 400, (n, 2))
    v = rng.uniform(-3, 3, (n, 2))
    wh = rng.uniform(20, 40, (n, 2))
    out = []
    for k in range(frames):
        seen = rng.random(n) > 0.15
        xy = np.vstack([p[seen] + rng.normal(0, 1.0, (int(seen.sum()), 2)),
                        rng.uniform(0, 400, (3, 2))])
        bwh = np.vstack([wh[seen], rng.uniform(20, 40, (3, 2))])
        perm = rng.permutation(xy.shape[0])
        out.append(Detections(k, xy[perm], bwh[perm]))
        p = p + v
    return out


def _run(frames: list, config=None) -> tuple[list, list]:
    from mvtrack.tracking import Tracker

    tracker = Tracker(config)
    outs = [tracker.step(d) for d in frames]
    return outs, [tracker.row_uids.copy(), tracker.tracks, tracker.pstate]


def _assert_same_frames(a: list, b: list) -> None:
    for fa_, fb in zip(a, b, strict=True):
        for name in ("track_id", "state", "det_index", "measured_xy", "filtered_xy",
                     "predicted_xy", "wh", "velocity"):
            np.testing.assert_array_equal(getattr(fa_, name), getattr(fb, name))


@pytest.mark.parametrize("predictor", ["kalman-cv", "kalman-ca"])
def test_deleting_only_the_last_rows_by_slicing_equals_gathering_the_kept_rows(
    predictor: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    from mvtrack.tracking import TrackerConfig
    from mvtrack.tracking import tracker as tr

    frames = _cluttered_frames(8, 60, 3)
    config = TrackerConfig(predictor=predictor)
    fast, fast_end = _run(frames, config)
    kept_rows = tr.kept_rows
    sliced = []

    def as_indices(delete):  # the general path: the kept rows as indices, always
        keep = kept_rows(delete)
        if isinstance(keep, slice):
            sliced.append(keep)
        return (~delete).nonzero()[0]

    monkeypatch.setattr(tr, "kept_rows", as_indices)
    general, general_end = _run(frames, config)
    assert sliced, "the scene should delete only trailing rows in some frames"
    _assert_same_frames(fast, general)
    np.testing.assert_array_equal(fast_end[0], general_end[0])
    np.testing.assert_array_equal(fast_end[1].ints, general_end[1].ints)
    np.testing.assert_array_equal(fast_end[1].floats, general_end[1].floats)


def test_kept_rows_are_a_slice_only_when_the_last_rows_end() -> None:
    from mvtrack.tracking import table as tr

    rng = np.random.default_rng(4)
    masks = [rng.random(rng.integers(1, 9)) > rng.uniform(0.2, 0.9) for _ in range(300)]
    masks += [np.array([False, False, True, True]), np.array([True] * 3)]
    slices = 0
    for delete in masks:
        keep = tr.kept_rows(delete)
        rows = np.arange(delete.size)
        np.testing.assert_array_equal(rows[keep], (~delete).nonzero()[0])
        slices += isinstance(keep, slice)
    assert 0 < slices < len(masks)


def test_table_and_state_slices_equal_the_gathered_rows() -> None:
    from mvtrack.tracking import table as tr
    from mvtrack.types import n_rows

    rng = np.random.default_rng(0)
    tab = tr.TrackTable(rng.integers(0, 9, (7, tr.N_INT)), rng.normal(size=(7, tr.N_FLOAT)))
    for stop in (0, 3, 7):
        a, b = tab.take(slice(0, stop)), tab.take(np.arange(stop))
        np.testing.assert_array_equal(a.ints, b.ints)
        np.testing.assert_array_equal(a.floats, b.floats)
    fast = KalmanCVPredictor().init(rng.normal(size=(7, 2)))
    general = make_predictor("kalman-ca").init(rng.normal(size=(7, 2)))
    for state in (fast, general):
        a, b = tr.take_state(state, slice(0, 4)), tr.take_state(state, np.arange(4))
        assert type(a) is type(state)
        for name in ("x", "P"):
            if hasattr(state, name):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert n_rows(a) == 4


def test_counters_with_a_mask_equal_counters_with_row_indices() -> None:
    from mvtrack.tracking.lifecycle import count_hits

    rng = np.random.default_rng(1)
    ints = rng.integers(0, 20, (9, 8))
    matched = rng.random(9) > 0.5
    held = matched | (rng.random(9) > 0.7)
    a, b = ints.copy(), ints.copy()
    count_hits(a, matched, held)
    count_hits(b, matched, held.nonzero()[0])
    np.testing.assert_array_equal(a, b)


def test_detection_rows_pad_with_nan_for_tracks_without_a_detection() -> None:
    from mvtrack.tracking import table as tr
    from mvtrack.types import Detections

    dets = Detections(0, [[1.0, 2.0], [3.0, 4.0]], [[5.0, 6.0], [7.0, 8.0]])
    rows = tr.detection_rows(dets).take(np.array([1, -1, 0]), 0)
    np.testing.assert_array_equal(rows[0], [3.0, 4.0, 7.0, 8.0])
    assert np.isnan(rows[1]).all()
    np.testing.assert_array_equal(rows[2], [1.0, 2.0, 5.0, 6.0])
    assert tr.detection_rows(Detections.empty(0)).shape == (1, 4)


def test_many_births_in_one_frame_get_consecutive_uids() -> None:
    from mvtrack.tracking import Tracker
    from mvtrack.types import Detections

    rng = np.random.default_rng(2)
    tracker = Tracker()
    tracker.step(Detections(0, rng.uniform(0, 1000, (40, 2)), np.full((40, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40))
    tracker.step(Detections(1, rng.uniform(2000, 3000, (50, 2)), np.full((50, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40, 90))
    assert (tracker.tracks.last_k == 1).all() and (tracker.tracks.prev_k == 1).all()
    assert (tracker.tracks.hits == 1).all() and (tracker.tracks.track_id == -1).all()


@pytest.mark.parametrize("n, m", [(6, 7), (100, 97), (900, 880)])  # dense, band, grid gating
def test_gate_pairs_size_gate_drops_exactly_the_pairs_of_another_size(n, m) -> None:
    rng = np.random.default_rng(n + 1)
    txy, dxy = _scene(rng, n, m, 12.0 * np.sqrt(n))
    f2 = rng.uniform(1.0, 4.0, (n, 2))
    twh, dwh = rng.uniform(10, 60, (n, 2)), rng.uniform(10, 60, (m, 2))
    ti, dj, sized = fa.gate_pairs(txy, dxy, f2, 100.0, (twh, dwh, 0.3))
    gi, gj, gated = fa.gate_pairs(txy, dxy, f2, 100.0, (twh, dwh, 0.3, 2.0))
    ratio = np.maximum(dwh[dj] / twh[ti], twh[ti] / dwh[dj]).max(axis=1)
    same = ratio <= 2.0
    assert same.any() and not same.all()
    np.testing.assert_array_equal(gi, ti[same])  # the others are left untouched
    np.testing.assert_array_equal(gj, dj[same])
    np.testing.assert_allclose(gated, sized[same])


@pytest.mark.parametrize("stretch", [False, True])
def test_dense_stages_with_a_size_gate_equal_sparse_gating(stretch: bool) -> None:
    rng = np.random.default_rng(9)
    for _ in range(20):
        txy, dxy = _scene(rng, 30, 33, 120.0)
        f2 = rng.uniform(1.0, 6.0, (30, 2)) if stretch else None
        twh, dwh = rng.uniform(10, 60, (30, 2)), rng.uniform(10, 60, (33, 2))
        size = (twh, dwh, 0.5, 1.8)
        t1, d1 = fa.optimal(*fa.gate_pairs(txy, dxy, f2, 25.0, size), 30, 33, 25.0)
        o1, p1 = fa.dense_optimal(txy, dxy, f2, 25.0, size)
        assert set(zip(o1.tolist(), p1.tolist(), strict=True)) == set(
            zip(t1.tolist(), d1.tolist(), strict=True)
        )
        mt, md, _ = fa.dense_two_stage(txy, dxy, f2, 25.0, 144.0, f2, size)
        lt = np.setdiff1d(np.arange(30), t1)
        ld = np.setdiff1d(np.arange(33), d1)
        size2 = (twh[lt], dwh[ld], 0.5, 1.8)
        t2, d2 = fa.optimal(
            *fa.gate_pairs(txy[lt], dxy[ld], None if f2 is None else f2[lt], 144.0, size2),
            lt.size, ld.size, 144.0,
        )
        want = set(zip(t1.tolist(), d1.tolist(), strict=True)) | set(
            zip(lt[t2].tolist(), ld[d2].tolist(), strict=True)
        )
        assert set(zip(mt.tolist(), md.tolist(), strict=True)) == want
        ratio = np.maximum(dwh[md] / twh[mt], twh[mt] / dwh[md]).max(axis=1)
        assert (ratio <= 1.8).all()


@pytest.mark.parametrize("gate, gate2", [(25.0, 144.0), (144.0, 25.0)])
def test_dense_two_stage_without_second_stage_pairs_equals_two_sparse_stages(
    gate: float, gate2: float
) -> None:
    # sparse scenes: most have no pair within gate2 besides the first stage's matches, which
    # dense_two_stage returns without building the second stage's matrix
    rng = np.random.default_rng(9)
    kinds = set()
    for _ in range(200):
        n = int(rng.integers(1, 12))
        txy, dxy = _scene(rng, n, n + int(rng.integers(0, n + 1)), 150.0)
        m = dxy.shape[0]
        mt, md, ud = fa.dense_two_stage(txy, dxy, None, gate, gate2)
        t1, d1 = fa.optimal(*fa.gate_pairs(txy, dxy, None, gate), n, m, gate)
        lt, ld = np.setdiff1d(np.arange(n), t1), np.setdiff1d(np.arange(m), d1)
        t2, d2 = fa.optimal(*fa.gate_pairs(txy[lt], dxy[ld], None, gate2), lt.size, ld.size,
                            gate2)
        kinds.add(t2.size > 0)
        want = set(zip(t1.tolist(), d1.tolist(), strict=True)) | set(
            zip(lt[t2].tolist(), ld[d2].tolist(), strict=True)
        )
        assert set(zip(mt.tolist(), md.tolist(), strict=True)) == want
        np.testing.assert_array_equal(ud, np.setdiff1d(np.arange(m), md))
    assert kinds == ({True, False} if gate < gate2 else {False})
