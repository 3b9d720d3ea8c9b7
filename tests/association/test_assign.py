"""Assignment rules: hand cases, brute force and dense references, permutation invariance."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from mvtrack.association.assign import (
    HIGH,
    LOW,
    NO_STAND,
    RULE_CODES,
    _small_block,
    assign,
    associate,
    solve,
    standing_pairs,
)
from mvtrack.association.gate import Gate
from mvtrack.association.pairs import quadratic_pairs
from mvtrack.association.view import TrackView


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


def test_optimal_equals_brute_force() -> None:
    """Blocks of up to 6 rows and columns: by enumeration (up to 4) and by SciPy beyond."""
    rng = np.random.default_rng(11)
    for _ in range(80):
        n, m = rng.integers(1, 7, 2)
        c = _random_gated(rng, n, m, rng.uniform(0.3, 1.0))
        for u in (None, 7.0, 30.0):
            a = assign(*_pairs(c), n, m, "optimal", unmatched_cost=u)
            if u is None:  # the default: twice the largest gated cost
                u = 2 * np.abs(c[np.isfinite(c)]).max() if np.isfinite(c).any() else 0.0
            got = a.cost.sum() + u * (n + m - 2 * len(a)) / 2
            np.testing.assert_allclose(got, _brute_force(c, u), rtol=1e-8, atol=1e-8)


def test_optimal_equals_dense_lsa_on_many_clusters() -> None:
    """Many clusters: same matching size and total cost as one dense LSA with u/2 dummies."""
    rng = np.random.default_rng(12)
    n = m = 200
    pos_t = rng.uniform(0, 400, (n, 2))
    pos_d = pos_t + rng.normal(0, 3, (m, 2))
    d2 = ((pos_t[:, None] - pos_d[None]) ** 2).sum(-1)
    c = np.where(d2 <= 100.0, d2, np.inf)
    u = 100.0
    a = assign(*_pairs(c), n, m, "optimal", unmatched_cost=u)
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




def test_small_blocks_are_solved_as_scipy_solves_them() -> None:
    """The enumeration of small conflicts gives SciPy's total cost on padded blocks."""
    rng = np.random.default_rng(14)
    for _ in range(300):
        r, c = rng.integers(1, 5, 2)
        u = 9.21
        block = rng.uniform(0, 12, (r, c))
        block[block > u] = u  # non-pairs cost u (left unmatched)
        ra, ca = _small_block(block, u)
        assert len(set(ca.tolist())) == ca.size  # exclusive
        got = block[ra, ca].sum() + u * (r - ra.size)
        pad = np.hstack([block, np.full((r, r), u)])  # every row may also stay unmatched
        rr, cc = linear_sum_assignment(pad)
        np.testing.assert_allclose(got, pad[rr, cc].sum(), rtol=1e-12, atol=1e-12)
        assert (block[ra, ca] < u).all()


def _scene(rng: np.random.Generator, n: int, m: int, size: float = 400.0):
    """Tracks with gates of various shapes and boxes, detections near some of them."""
    cx = rng.uniform(0, size, (n, 2))
    a, c = rng.uniform(4, 200, n), rng.uniform(4, 200, n)
    b = rng.uniform(-0.8, 0.8, n) * np.sqrt(a * c)
    S = np.stack([a, b, c], axis=1)
    twh = rng.uniform(10, 80, (n, 2))
    near = rng.integers(0, n, m)
    dxy = np.where(rng.random((m, 1)) < 0.7, cx[near] + rng.normal(0, 8, (m, 2)),
                   rng.uniform(0, size, (m, 2)))
    dwh = twh[near] * rng.uniform(0.7, 1.4, (m, 2))
    return cx, S, twh, dxy, dwh


def _reference_pairs(cx, S, twh, dxy, dwh, gate, size_w):
    """The gate's values by the Gate object's matrix (NumPy), thresholded."""
    cov = np.zeros((len(cx), 2, 2))
    cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 0], cov[:, 1, 1] = S[:, 0], S[:, 1], S[:, 1], S[:, 2]
    view = TrackView(cx, cov, cov, np.zeros_like(cx), twh)
    value = Gate.build("mahalanobis", view, gate, size_weight=size_w).matrix(dxy, dwh)
    ti, dj = np.nonzero(value <= gate)
    return ti, dj, value[ti, dj]


@pytest.mark.parametrize("n,m", [(5, 6), (40, 50), (300, 280)])  # dense tests, grid, grid
@pytest.mark.parametrize("size_w", [0.0, 16.0])
def test_quadratic_pairs_are_exactly_the_pairs_inside_the_gate(n, m, size_w) -> None:
    rng = np.random.default_rng(n + m)
    cx, S, twh, dxy, dwh = _scene(rng, n, m, size=60.0 * np.sqrt(n))
    tsel, dsel = np.ones(n, bool), np.ones(m, bool)
    ti, dj, cost = quadratic_pairs(cx, S, twh, tsel, dxy, dwh, dsel, 9.21, size_w)
    rt, rd, rc = _reference_pairs(cx, S, twh, dxy, dwh, 9.21, size_w)
    assert ti.size > n // 4  # the scene has pairs
    np.testing.assert_array_equal(ti, rt)  # sorted by track, then detection
    np.testing.assert_array_equal(dj, rd)
    np.testing.assert_allclose(cost, rc, rtol=1e-9)
    # a selection of tracks and detections: the same pairs restricted to it
    tsel, dsel = rng.random(n) < 0.5, rng.random(m) < 0.5
    ti2, dj2, _ = quadratic_pairs(cx, S, twh, tsel, dxy, dwh, dsel, 9.21, size_w)
    keep = tsel[rt] & dsel[rd]
    np.testing.assert_array_equal(ti2, rt[keep])
    np.testing.assert_array_equal(dj2, rd[keep])


def test_the_compiled_kernels_equal_their_plain_functions() -> None:
    """The one source: compiled and interpreted give the same pairs and assignment."""
    rng = np.random.default_rng(21)
    for n, m in ((8, 9), (120, 110)):
        cx, S, twh, dxy, dwh = _scene(rng, n, m, size=50.0 * np.sqrt(n))
        dclass = rng.choice(np.array([0, 1, 2], np.int8), m, p=[0.1, 0.3, 0.6])
        # a third of the tracks held where they stand, in a box about their centre
        stand = np.full((n, 4), np.nan)
        held = rng.random(n) < 0.3
        stand[held] = np.column_stack([cx[held] + rng.normal(0, 5, (held.sum(), 2)), twh[held]])
        for rule in RULE_CODES.values():
            args = (cx, S, np.zeros((0, 0)), twh, dxy, dwh, dclass, 9.21, 16.0, rule, stand)
            np.testing.assert_array_equal(associate(*args), associate.py_func(*args))


def test_high_detections_first_then_the_low_ones_for_the_tracks_left_over() -> None:
    """Two tracks, one high box in both gates, one low box near the second: the first stage
    gives the high box to the nearer track, the second the low box to the other; a dropped
    box is never taken."""
    cx = np.array([[0.0, 0.0], [10.0, 0.0]])
    S = np.array([[25.0, 0.0, 25.0], [25.0, 0.0, 25.0]])
    twh = np.full((2, 2), 20.0)
    dxy = np.array([[2.0, 0.0], [9.0, 0.0], [11.0, 0.0]])
    dwh = np.full((3, 2), 20.0)
    no = np.zeros((0, 0))
    opt = RULE_CODES["optimal"]
    # the low box (row 1) sits nearer the second track than the high one does, and yet the
    # second track takes it only in the second stage, after the first track took the high box
    dclass = np.array([HIGH, LOW, 0], np.int8)
    got = associate(cx, S, no, twh, dxy, dwh, dclass, 9.21, 0.0, opt, NO_STAND)
    assert got.tolist() == [0, 1]
    dclass = np.array([HIGH, 0, 0], np.int8)  # dropped boxes are never taken
    got = associate(cx, S, no, twh, dxy, dwh, dclass, 9.21, 0.0, opt, NO_STAND)
    assert got.tolist() == [0, -1]
    # and with all three high, the optimal assignment gives each track its nearest
    dclass = np.full(3, HIGH, np.int8)
    got = associate(cx, S, no, twh, dxy, dwh, dclass, 9.21, 0.0, opt, NO_STAND)
    assert got.tolist() == [0, 1]


def test_a_held_track_takes_only_a_detection_centred_in_the_box_it_stands_in() -> None:
    """Paper 1's 20 px circle about a track held at (100, 100) in a 16 × 10 box holds two
    detections: A 6 px below (outside the box's half height of 5) and B 7 px to the right
    (inside its half width of 8). Nearest, a free track takes A; held, it takes B (the pair
    with A is dropped before the assignment, not the assignment undone), and with A alone
    it takes none. A free track beside it (at x = 120) takes B either way."""
    cx = np.array([[100.0, 100.0], [120.0, 100.0]])
    S = np.array([[1.0, 0.0, 1.0]] * 2)  # the Euclidean gate: C = I, g in px²
    twh = np.array([[16.0, 10.0], [16.0, 10.0]])
    dxy = np.array([[100.0, 106.0], [107.0, 100.0]])  # A, B
    dwh = np.full((2, 2), 10.0)
    no, near = np.zeros((0, 0)), RULE_CODES["nearest"]
    dclass = np.full(2, HIGH, np.int8)
    stand = np.array([[100.0, 100.0, 16.0, 10.0], [np.nan] * 4])
    args = (cx, S, no, twh, dxy, dwh, dclass, 400.0, 0.0, near)
    assert associate(*args, NO_STAND).tolist() == [0, 1]
    assert associate(*args, stand).tolist() == [1, 1]
    a_only = (cx, S, no, twh, dxy[:1], dwh[:1], dclass[:1], 400.0, 0.0, near)
    assert associate(*a_only, NO_STAND).tolist() == [0, -1]  # A lies 20.9 px from x = 120
    assert associate(*a_only, stand).tolist() == [-1, -1]
    # the pairs themselves, compiled and plain
    ti, dj, c = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1]), np.array([36.0, 49, 436, 169])
    for fn in (standing_pairs, standing_pairs.py_func):
        kt, kd, kc = fn(ti, dj, c, stand, dxy)
        assert kt.tolist() == [0, 1, 1] and kd.tolist() == [1, 0, 1]
        assert kc.tolist() == [49.0, 436.0, 169.0]
        assert fn(ti, dj, c, NO_STAND, dxy)[1].tolist() == [0, 1, 0, 1]


def test_solve_writes_only_the_matched_tracks() -> None:
    det_index = np.full(3, -7, np.intp)
    ti, dj, c = np.array([1]), np.array([2]), np.array([0.5])
    solve(ti, dj, c, 3, 3, RULE_CODES["optimal"], 9.21, det_index)
    assert det_index.tolist() == [-7, 2, -7]
