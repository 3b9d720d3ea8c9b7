"""The disc-gate association (:mod:`mvtrack.association.discs`) equals the general code of
:mod:`mvtrack.association` (gating values and the penalised optimal assignment), brute force
on tiny problems, and hand computations for what only it has (per-axis factors, size term,
size gate and the partial views it lets through, the two dense stages)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mvtrack.association import TrackView, assign, candidate_pairs
from mvtrack.association import discs as fa


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


@pytest.mark.parametrize("n, m", [(6, 7), (100, 97), (900, 880)])  # dense, band, grid gating
def test_gate_pairs_size_gate_drops_exactly_the_pairs_of_another_size(n, m) -> None:
    rng = np.random.default_rng(n + 1)
    txy, dxy = _scene(rng, n, m, 12.0 * np.sqrt(n))
    f2 = rng.uniform(1.0, 4.0, (n, 2))
    twh, dwh = rng.uniform(10, 60, (n, 2)), rng.uniform(10, 60, (m, 2))
    ti, dj, sized = fa.gate_pairs(txy, dxy, f2, 100.0, (twh, dwh, 0.3))
    gi, gj, gated = fa.gate_pairs(txy, dxy, f2, 100.0, (twh, dwh, 0.3, 2.0))
    ratio = np.maximum(dwh[dj] / twh[ti], twh[ti] / dwh[dj])
    same = (ratio[:, 1] <= 2.0) & (ratio[:, 0] <= 4.0)  # heights ρ, widths ρ²
    assert same.any() and not same.all()
    np.testing.assert_array_equal(gi, ti[same])  # the others are left untouched
    np.testing.assert_array_equal(gj, dj[same])
    np.testing.assert_allclose(gated, sized[same])


def _dense_equals_sparse_stages(txy, dxy, f2, twh, dwh, tail, g1, g2):
    """Both dense solvers with the size term ``(twh, dwh, *tail)`` give what sparse gating and
    the penalised assignment give, stage by stage; returns the two stages' pairs."""
    n, m = txy.shape[0], dxy.shape[0]
    size = (twh, dwh, *tail)
    t1, d1 = fa.optimal(*fa.gate_pairs(txy, dxy, f2, g1, size), n, m, g1)
    o1, p1 = fa.dense_optimal(txy, dxy, f2, g1, size)
    assert set(zip(o1.tolist(), p1.tolist(), strict=True)) == set(
        zip(t1.tolist(), d1.tolist(), strict=True)
    )
    mt, md, _ = fa.dense_two_stage(txy, dxy, f2, g1, g2, f2, size)
    lt = np.setdiff1d(np.arange(n), t1)
    ld = np.setdiff1d(np.arange(m), d1)
    t2, d2 = fa.optimal(
        *fa.gate_pairs(txy[lt], dxy[ld], None if f2 is None else f2[lt], g2,
                       (twh[lt], dwh[ld], *tail)),
        lt.size, ld.size, g2,
    )
    want = set(zip(t1.tolist(), d1.tolist(), strict=True)) | set(
        zip(lt[t2].tolist(), ld[d2].tolist(), strict=True)
    )
    assert set(zip(mt.tolist(), md.tolist(), strict=True)) == want
    return mt, md


@pytest.mark.parametrize("stretch", [False, True])
def test_dense_stages_with_a_size_gate_equal_sparse_gating(stretch: bool) -> None:
    rng = np.random.default_rng(9)
    for _ in range(20):
        txy, dxy = _scene(rng, 30, 33, 120.0)
        f2 = rng.uniform(1.0, 6.0, (30, 2)) if stretch else None
        twh, dwh = rng.uniform(10, 60, (30, 2)), rng.uniform(10, 60, (33, 2))
        mt, md = _dense_equals_sparse_stages(txy, dxy, f2, twh, dwh, (0.5, 1.8), 25.0, 144.0)
        ratio = np.maximum(dwh[md] / twh[mt], twh[mt] / dwh[md])
        assert (ratio[:, 1] <= 1.8).all() and (ratio[:, 0] <= 1.8**2).all()


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


def test_partial_views_by_hand() -> None:
    # a 60 × 150 px track at (100, 100): bottom edge 175; ε = 0.15 → 22.5 px on the bottom
    # edge, and |dx| + w_d / 2 <= 1.15 × 30 = 34.5 px along x
    twh = np.array([60.0, 150.0])
    cases = [  # (detection centre, size), partial?
        ((100.0, 130.0), (40.0, 90.0), True),  # bottom edges equal
        ((100.0, 152.0), (40.0, 90.0), True),  # bottom 197: 22 px below
        ((100.0, 153.0), (40.0, 90.0), False),  # 23 px below
        ((100.0, 100.0), (40.0, 90.0), False),  # bottom 145: a person farther away
        ((114.0, 130.0), (40.0, 90.0), True),  # 14 + 20 = 34 <= 34.5
        ((115.0, 130.0), (40.0, 90.0), False),  # 35 > 34.5
        ((100.0, 90.0), (80.0, 170.0), False),  # larger: never a partial view
    ]
    for (x, y), wh, want in cases:
        got = fa.partial_views(twh, np.array(wh), np.array(x - 100.0), np.array(y - 100.0), 0.15)
        assert bool(got) is want, (x, y, wh)


def _partial_scene(rng, n, m, spread):
    """A scene where the first third of the tracks have a detection on their foot point that
    is a partial view (smaller than the size gate allows) and the rest random boxes."""
    txy, dxy = _scene(rng, n, m, spread)
    twh = rng.uniform(20, 60, (n, 2))
    dwh = rng.uniform(10, 60, (m, 2))
    k = min(n // 3, m)
    dwh[:k] = twh[:k] * rng.uniform(0.3, 0.6, (k, 2))
    dxy[:k, 0] = txy[:k, 0] + rng.uniform(-0.1, 0.1, k) * twh[:k, 0]
    dxy[:k, 1] = txy[:k, 1] + 0.5 * (twh[:k, 1] - dwh[:k, 1]) + rng.normal(0, 2, k)
    return txy, dxy, twh, dwh


@pytest.mark.parametrize("n, m", [(6, 7), (100, 97), (900, 880)])  # dense, band, grid gating
def test_gate_pairs_lets_exactly_the_partial_views_through_the_size_gate(n, m) -> None:
    rng = np.random.default_rng(n + 5)
    txy, dxy, twh, dwh = _partial_scene(rng, n, m, 12.0 * np.sqrt(n))
    big = 1e6  # a gate that passes every pair: only the size decides
    ti, dj, _ = fa.gate_pairs(txy, dxy, None, big, (twh, dwh, 0.0, 1.5, 0.15))
    got = set(zip(ti.tolist(), dj.tolist(), strict=True))
    want = set()
    for i in range(n):  # by hand, pair by pair
        tw, th = twh[i]
        for j in range(m):
            (dw, dh), (dx, dy) = dwh[j], dxy[j] - txy[i]
            same = max(dh / th, th / dh) <= 1.5 and max(dw / tw, tw / dw) <= 1.5**2
            part = (dh < th and abs(dy + (dh - th) / 2) <= 0.15 * th
                    and abs(dx) + dw / 2 <= 1.15 * tw / 2)
            if same or part:
                want.add((i, j))
    assert got == want
    assert any(max(twh[i] / dwh[j]) > 1.5 for i, j in want)  # partial views were tested


@pytest.mark.parametrize("stretch", [False, True])
def test_dense_stages_with_partial_views_equal_sparse_gating(stretch: bool) -> None:
    rng = np.random.default_rng(11)
    partial = 0
    for _ in range(20):
        txy, dxy, twh, dwh = _partial_scene(rng, 30, 33, 120.0)
        f2 = rng.uniform(1.0, 6.0, (30, 2)) if stretch else None
        mt, md = _dense_equals_sparse_stages(txy, dxy, f2, twh, dwh, (0.5, 1.5, 0.15), 400.0,
                                             900.0)
        partial += np.count_nonzero((twh[mt] / dwh[md]).max(axis=1) > 1.5)
    assert partial > 20  # matched partial views, not only pairs of one size
