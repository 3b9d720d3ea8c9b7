"""Assignment rules: hand cases, brute force and dense references, permutation invariance."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from mvtrack.association.assign import assign


def _pairs(c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gated pairs of a dense cost matrix with ``inf`` for forbidden entries."""
    ti, dj = np.nonzero(np.isfinite(c))
    return ti, dj, c[ti, dj]


# t0-d0 1, t0-d1 2, t1-d0 2, t1-d1 10: greedy takes 1 then 10 (= 11), optimal 2 + 2 (= 4)
HAND = np.array([[1.0, 2.0], [2.0, 10.0]])


def test_nearest_is_non_exclusive() -> None:
    c = np.array([[1.0, 5.0, np.inf], [2.0, np.inf, np.inf], [np.inf, np.inf, np.inf]])
    a = assign(*_pairs(c), 3, 3, "nearest")
    assert a.track.tolist() == [0, 1] and a.det.tolist() == [0, 0]
    assert a.unmatched_tracks.tolist() == [2]
    assert a.unmatched_dets.tolist() == [1, 2]


def test_nearest_ties_go_to_the_lower_detection_row() -> None:
    c = np.array([[3.0, 3.0, 3.0]])
    ti, dj, cost = _pairs(c)
    order = np.array([2, 0, 1])
    a = assign(ti[order], dj[order], cost[order], 1, 3, "nearest")
    assert a.det.tolist() == [0]


def test_greedy_and_optimal_hand_case() -> None:
    g = assign(*_pairs(HAND), 2, 2, "greedy")
    assert list(zip(g.track, g.det, strict=True)) == [(0, 0), (1, 1)]
    assert g.cost.sum() == 11.0
    o = assign(*_pairs(HAND), 2, 2, "optimal")
    assert list(zip(o.track, o.det, strict=True)) == [(0, 1), (1, 0)]
    assert o.cost.sum() == 4.0
    n = assign(*_pairs(HAND), 2, 2, "nearest")
    assert n.det.tolist() == [0, 0]


def test_optimal_trades_matches_against_cost_with_unmatched_cost() -> None:
    # t0-d0 0; t0-d1 8; t1-d0 8; t1-d1 forbidden
    c = np.array([[0.0, 8.0], [8.0, np.inf]])
    a = assign(*_pairs(c), 2, 2, "optimal")  # default u = 16: 16 < 0 + 16 + ε, two matches
    assert len(a) == 2
    b = assign(*_pairs(c), 2, 2, "optimal", unmatched_cost=10.0)
    assert len(b) == 1 and b.track.tolist() == [0] and b.det.tolist() == [0]  # 0 + 10 < 16
    # a pair is worth matching only when its cost is below u
    b = assign(*_pairs(np.array([[5.0]])), 1, 1, "optimal", unmatched_cost=4.0)
    assert len(b) == 0 and b.unmatched_tracks.tolist() == [0]


def _greedy_reference(c: np.ndarray) -> set[tuple[int, int]]:
    ti, dj, cost = _pairs(c)
    used_t, used_d, out = set(), set(), set()
    for p in np.lexsort((dj, ti, cost)):
        if ti[p] not in used_t and dj[p] not in used_d:
            used_t.add(ti[p])
            used_d.add(dj[p])
            out.add((int(ti[p]), int(dj[p])))
    return out


def _brute_force(c: np.ndarray, u: float) -> float:
    """Least cost + u/2 per unmatched track and detection over all exclusive matchings."""
    n, m = c.shape
    best = np.inf
    for k in range(min(n, m) + 1):
        for rows in itertools.combinations(range(n), k):
            for cols in itertools.permutations(range(m), k):
                s = sum(c[r, q] for r, q in zip(rows, cols, strict=True))
                best = min(best, s + u * (n + m - 2 * k) / 2)
    return float(best)


def _random_gated(rng: np.random.Generator, n: int, m: int, density: float) -> np.ndarray:
    c = rng.uniform(0, 10, (n, m))
    c[rng.random((n, m)) > density] = np.inf
    return c


@pytest.mark.parametrize("solver", ["dense", "sparse"])
def test_optimal_equals_brute_force(solver: str) -> None:
    rng = np.random.default_rng(11)
    for _ in range(60):
        n, m = rng.integers(1, 5, 2)
        c = _random_gated(rng, n, m, rng.uniform(0.3, 1.0))
        for u in (None, 7.0, 30.0):
            a = assign(*_pairs(c), n, m, "optimal", unmatched_cost=u, solver=solver)
            if u is None:  # the default: twice the largest gated cost
                u = 2 * np.abs(c[np.isfinite(c)]).max() if np.isfinite(c).any() else 0.0
            got = a.cost.sum() + u * (n + m - 2 * len(a)) / 2
            np.testing.assert_allclose(got, _brute_force(c, u), rtol=1e-8, atol=1e-8)


@pytest.mark.parametrize("solver", ["dense", "sparse", "auto"])
def test_optimal_equals_dense_lsa_on_many_clusters(solver: str) -> None:
    """Many clusters: same matching size and total cost as one dense LSA with u/2 dummies."""
    rng = np.random.default_rng(12)
    n = m = 200
    pos_t = rng.uniform(0, 400, (n, 2))
    pos_d = pos_t + rng.normal(0, 3, (m, 2))
    d2 = ((pos_t[:, None] - pos_d[None]) ** 2).sum(-1)
    c = np.where(d2 <= 100.0, d2, np.inf)
    u = 100.0
    a = assign(*_pairs(c), n, m, "optimal", unmatched_cost=u, solver=solver)
    aug = np.full((n + m, m + n), np.inf)
    aug[:n, :m] = c
    aug[np.arange(n), m + np.arange(n)] = u / 2
    aug[n + np.arange(m), np.arange(m)] = u / 2
    aug[n:, m:] = 0.0
    r, k = linear_sum_assignment(aug)
    real = (r < n) & (k < m)
    assert len(a) == real.sum() > 150
    assert a.cost.sum() == pytest.approx(c[r[real], k[real]].sum(), rel=1e-9)
    assert len(set(a.det.tolist())) == len(a)  # exclusive


def test_greedy_equals_sequential_reference() -> None:
    rng = np.random.default_rng(13)
    for _ in range(50):
        n, m = rng.integers(1, 12, 2)
        c = _random_gated(rng, n, m, 0.5)
        c[rng.random((n, m)) < 0.2] = 1.0  # ties
        a = assign(*_pairs(c), n, m, "greedy")
        assert set(zip(a.track.tolist(), a.det.tolist(), strict=True)) == _greedy_reference(c)


@settings(max_examples=40, deadline=None)
@given(
    st.integers(1, 8),
    st.integers(1, 8),
    st.integers(0, 2**32 - 1),
    st.sampled_from(["nearest", "greedy", "optimal"]),
)
def test_assignment_invariant_under_detection_permutation(
    n: int, m: int, seed: int, rule: str
) -> None:
    rng = np.random.default_rng(seed)
    c = _random_gated(rng, n, m, 0.6)
    perm = rng.permutation(m)  # new column q holds old detection perm[q]
    a = assign(*_pairs(c), n, m, rule)  # type: ignore[arg-type]
    b = assign(*_pairs(c[:, perm]), n, m, rule)  # type: ignore[arg-type]
    assert a.track.tolist() == b.track.tolist()
    assert a.det.tolist() == perm[b.det].tolist()
    assert sorted(a.unmatched_dets.tolist()) == sorted(perm[b.unmatched_dets].tolist())


def test_empty_and_all_unmatched() -> None:
    e = np.zeros(0, dtype=int)
    for rule in ("nearest", "greedy", "optimal"):
        a = assign(e, e, np.zeros(0), 3, 2, rule)  # type: ignore[arg-type]
        assert len(a) == 0
        assert a.unmatched_tracks.tolist() == [0, 1, 2]
        assert a.unmatched_dets.tolist() == [0, 1]
        assert a.det_of_track(3).tolist() == [-1, -1, -1]


def test_bad_input_raises() -> None:
    with pytest.raises(ValueError, match="unknown rule"):
        assign([0], [0], [1.0], 1, 1, "hungarian")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="out of range"):
        assign([1], [0], [1.0], 1, 1)
    with pytest.raises(ValueError, match="NaN"):
        assign([0], [0], [np.nan], 1, 1)
    with pytest.raises(ValueError, match="equal length"):
        assign([0, 0], [0], [1.0], 1, 1)


@pytest.mark.parametrize("rounds", [1, 12])
def test_components_match_scipy_including_long_chains(rounds: int, monkeypatch) -> None:
    """Label propagation, and (with one round allowed) the SciPy fallback."""
    import sys

    from scipy.sparse import coo_array
    from scipy.sparse.csgraph import connected_components

    module = sys.modules["mvtrack.association.optimal"]
    monkeypatch.setattr(module, "_PROPAGATION_ROUNDS", rounds)
    _components = module._components

    rng = np.random.default_rng(14)
    chain_t = np.repeat(np.arange(60), 2)[1:]  # a chain t0-d0-t1-d1-...
    chain_d = np.repeat(np.arange(60), 2)[:-1]
    cases = [(chain_t, chain_d, 60, 60)]
    for _ in range(20):
        n, m = rng.integers(1, 40, 2)
        p = rng.integers(0, 2 * (n + m))
        cases.append((rng.integers(0, n, p), rng.integers(0, m, p), n, m))
    for ti, dj, n, m in cases:
        lab = _components(ti, dj, n, m)
        g = coo_array((np.ones(ti.size), (ti, n + dj)), shape=(n + m, n + m))
        k, ref = connected_components(g, directed=False)
        # same partition, labelled by the smallest node of each component
        assert np.unique(lab).size == k
        assert np.unique(np.stack([lab, ref]), axis=1).shape[1] == k
        assert np.all(lab <= np.arange(n + m)) and np.all(lab[lab] == lab)


def _augmented_optimum(c: np.ndarray, u: float) -> float:
    """Reference: one dense LSA on the (N+M)² cost-of-non-assignment matrix."""
    n, m = c.shape
    aug = np.full((n + m, m + n), np.inf)
    aug[:n, :m] = np.where(c < u, c, np.inf)
    aug[np.arange(n), m + np.arange(n)] = u / 2
    aug[n + np.arange(m), np.arange(m)] = u / 2
    aug[n:, m:] = 0.0
    r, k = linear_sum_assignment(aug)
    return float(aug[r, k].sum())


@pytest.mark.parametrize("solver", ["auto", "dense", "sparse"])
@pytest.mark.parametrize("integer_costs", [False, True])
@pytest.mark.parametrize("dense_frame_nodes", [0, 128])
def test_optimal_with_leaf_peeling_equals_reference_on_geometric_scenes(
    solver: str, integer_costs: bool, dense_frame_nodes: int, monkeypatch
) -> None:
    """Frames above the dense-frame size: peeling + clusters + solver, ties included.

    ``DENSE_FRAME_NODES = 0`` forces the per-cluster paths after the peeling.
    """
    import sys

    monkeypatch.setattr(
        sys.modules["mvtrack.association.optimal"], "DENSE_FRAME_NODES", dense_frame_nodes
    )
    rng = np.random.default_rng(15)
    for _ in range(6):
        n = int(rng.integers(80, 160))
        m = int(rng.integers(80, 160))
        pos_t = rng.uniform(0, 300, (n, 2))
        pos_d = np.vstack(
            [
                pos_t[: min(n, m)] + rng.normal(0, 4, (min(n, m), 2)),
                rng.uniform(0, 300, (m - min(n, m), 2)),
            ]
        )
        d2 = ((pos_t[:, None] - pos_d[None]) ** 2).sum(-1)
        if integer_costs:
            d2 = np.round(d2 / 20.0)
        c = np.where(d2 <= (15.0 if integer_costs else 300.0), d2, np.inf)
        for u in (None, float(np.nanmax(np.where(np.isfinite(c), c, np.nan))) * 0.7):
            a = assign(*_pairs(c), n, m, "optimal", unmatched_cost=u, solver=solver)
            uu = 2 * np.abs(c[np.isfinite(c)]).max() * (1 + 1e-9) + 1e-12 if u is None else u
            got = a.cost.sum() + uu * (n + m - 2 * len(a)) / 2
            assert got == pytest.approx(_augmented_optimum(c, uu), rel=1e-9, abs=1e-9)
            assert len(set(a.det.tolist())) == len(a) == len(set(a.track.tolist()))


@pytest.mark.parametrize("u", [None, 6.0, 12.0])
def test_many_two_by_two_clusters_match_the_reference(u: float | None, monkeypatch) -> None:
    """Block-diagonal frame of 2 × 2 conflicts (the closed-form path), some with a pair cut."""
    import sys

    module = sys.modules["mvtrack.association.optimal"]
    rng = np.random.default_rng(16)
    k = 120
    c = np.full((2 * k, 2 * k), np.inf)
    for b in range(k):
        block = rng.uniform(0, 10, (2, 2))
        if b % 3 == 0:
            block[rng.integers(2), rng.integers(2)] = np.inf
        c[2 * b : 2 * b + 2, 2 * b : 2 * b + 2] = block
    perm_t, perm_d = rng.permutation(2 * k), rng.permutation(2 * k)
    c = c[perm_t][:, perm_d]  # clusters scattered over the rows
    calls = {"n": 0}
    original = module._solve_2x2

    def counting(*args):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        return original(*args)

    monkeypatch.setattr(module, "_solve_2x2", counting)
    a = assign(*_pairs(c), 2 * k, 2 * k, "optimal", unmatched_cost=u)
    assert calls["n"] == 1
    uu = 2 * np.abs(c[np.isfinite(c)]).max() * (1 + 1e-9) + 1e-12 if u is None else u
    got = a.cost.sum() + uu * (4 * k - 2 * len(a)) / 2
    assert got == pytest.approx(_augmented_optimum(c, uu), rel=1e-9)
