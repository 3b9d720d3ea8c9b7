"""The ``iou`` gate's pair search: exactly the pairs of the dense ``1 − IoU`` matrix (the
NumPy distance of :mod:`mvtrack.association.distances`), found among overlapping boxes."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association.assign import HIGH, LOW, NO_STAND, RULE_CODES, associate
from mvtrack.association.gate import Gate
from mvtrack.association.pairs import (
    _DENSE_TESTS,
    BY_MATRIX,
    BY_OVERLAP,
    frame_pairs,
    overlap_pairs,
)
from mvtrack.association.view import TrackView


def _boxes(rng: np.random.Generator, n: int, m: int, crowd: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Track boxes of 8–120 px (a few of 400 px) in a field sized for ``crowd`` boxes per
    box area; detections near some tracks (jittered position and size), the rest anywhere."""
    side = 50.0 * np.sqrt(max(n, m, 1) / crowd)
    cx = rng.uniform(0, side, (n, 2))
    twh = rng.uniform(8, 120, (n, 2))
    if n > 4:
        twh[rng.integers(0, n, 2)] = 400.0  # boxes that cover many grid cells
    near = rng.integers(0, max(n, 1), m)
    dxy = rng.uniform(0, side, (m, 2))
    dwh = rng.uniform(8, 120, (m, 2))
    if n:
        close = rng.random(m) < 0.6
        dxy[close] = cx[near[close]] + rng.normal(0, 6, (int(close.sum()), 2))
        dwh[close] = twh[near[close]] * rng.uniform(0.85, 1.2, (int(close.sum()), 2))
    return cx, twh, dxy, dwh


def _dense(cx, twh, dxy, dwh, gate, size_w):
    """The reference: the gate's dense matrix (NumPy ``iou_cost`` + size term), thresholded."""
    n = cx.shape[0]
    view = TrackView(cx, np.broadcast_to(np.eye(2), (n, 2, 2)),
                     np.broadcast_to(np.eye(2), (n, 2, 2)), np.zeros((n, 2)), twh)
    with np.errstate(divide="ignore", invalid="ignore"):  # boxes of no size: ±inf, NaN
        full = Gate.build("iou", view, gate, size_weight=size_w).matrix(dxy, dwh)
    ti, dj = np.nonzero(full <= gate)
    return ti, dj, full[ti, dj]


def _check(got, ref, size_w):
    np.testing.assert_array_equal(got[0], ref[0])  # the same pairs, sorted by track, then det
    np.testing.assert_array_equal(got[1], ref[1])
    if size_w == 0.0:
        np.testing.assert_array_equal(got[2], ref[2])  # the same operations: the same bits
    else:  # the logarithm of the size term: libm's against NumPy's, to rounding
        np.testing.assert_allclose(got[2], ref[2], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    "n,m",
    [(0, 0), (0, 7), (6, 0), (1, 1), (9, 11), (60, 64),  # pair by pair
     (70, 80), (300, 280), (1500, 1400)],  # through the grid
)
@pytest.mark.parametrize("crowd", [0.3, 3.0])  # sparse, and boxes over each other
@pytest.mark.parametrize("size_w", [0.0, 16.0])
def test_overlap_pairs_are_the_dense_matrix_pairs(n: int, m: int, crowd: float,
                                                  size_w: float) -> None:
    rng = np.random.default_rng(7 * n + m + int(10 * crowd))
    cx, twh, dxy, dwh = _boxes(rng, n, m, crowd)
    for gate in (0.7, 0.3, 0.95):
        ref = _dense(cx, twh, dxy, dwh, gate, size_w)
        got = overlap_pairs(cx, twh, np.ones(n, bool), dxy, dwh, np.ones(m, bool), gate,
                            size_w)
        _check(got, ref, size_w)
        if n * m > 2 * _DENSE_TESTS and gate == 0.7:
            assert ref[0].size > n // 8  # the scene has pairs
        # a selection of tracks and detections (the tracker's stages): the same pairs
        # restricted to it
        tsel, dsel = rng.random(n) < 0.6, rng.random(m) < 0.5
        got = overlap_pairs(cx, twh, tsel, dxy, dwh, dsel, gate, size_w)
        keep = tsel[ref[0]] & dsel[ref[1]]
        _check(got, (ref[0][keep], ref[1][keep], ref[2][keep]), size_w)


def test_edge_cases_of_overlap() -> None:
    """Equal boxes (value 0), boxes that only touch (IoU 0), one inside another, boxes of
    zero size, a box far outside every cell: as the dense matrix; at gate 1 every pair
    passes (a value 1 − 0 is inside), in a frame large enough for the grid."""
    rng = np.random.default_rng(11)
    cx, twh, dxy, dwh = _boxes(rng, 90, 70, 1.0)  # 6300 tests: the grid
    dxy[0], dwh[0] = cx[0], twh[0]  # the same box
    dxy[1], dwh[1] = cx[1] + [twh[1, 0], 0.0], twh[1]  # touching on the right
    dxy[2], dwh[2] = cx[2], twh[2] * 0.5  # inside
    dwh[3] = 0.0  # a point
    twh[4] = 0.0
    cx[5] = [-1e6, 3e6]  # far outside the detections' extent
    for gate, size_w in ((0.7, 0.0), (0.999, 0.0), (0.7, 4.0), (1.0, 0.0), (1.5, 4.0)):
        ref = _dense(cx, twh, dxy, dwh, gate, size_w)
        got = overlap_pairs(cx, twh, np.ones(90, bool), dxy, dwh, np.ones(70, bool), gate,
                            size_w)
        _check(got, ref, size_w)
        if gate >= 1.0 and size_w == 0.0:
            assert got[0].size == 90 * 70
    ti, dj, c = overlap_pairs(cx, twh, np.ones(90, bool), dxy, dwh, np.ones(70, bool), 0.7,
                              0.0)
    assert ti[0] == 0 and dj[0] == 0 and c[0] < 1e-12  # the same box: 1 − IoU = 0
    assert (1, 1) not in zip(ti.tolist(), dj.tolist(), strict=True)  # touching: IoU 0


def test_the_compiled_search_equals_its_plain_function() -> None:
    rng = np.random.default_rng(12)
    cx, twh, dxy, dwh = _boxes(rng, 200, 190, 2.0)
    args = (cx, twh, np.ones(200, bool), dxy, dwh, rng.random(190) < 0.8, 0.7, 16.0)
    for a, b in zip(overlap_pairs(*args), overlap_pairs.py_func(*args), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("rule", list(RULE_CODES))
def test_associate_by_overlap_equals_associate_by_the_dense_matrix(rule: str) -> None:
    """The tracker's association of a frame with the ``iou`` gate: the pairs found among
    overlapping boxes give the same assignment as the dense matrix, stage by stage."""
    rng = np.random.default_rng(13)
    for n, m in ((8, 9), (150, 160), (700, 650)):
        cx, twh, dxy, dwh = _boxes(rng, n, m, 2.0)
        dclass = rng.choice(np.array([0, LOW, HIGH], np.int8), m, p=[0.1, 0.3, 0.6])
        S = np.full((n, 3), np.nan)  # an iou gate has no covariance
        for size_w in (0.0, 16.0):
            view = TrackView(cx, np.broadcast_to(np.eye(2), (n, 2, 2)),
                             np.broadcast_to(np.eye(2), (n, 2, 2)), np.zeros((n, 2)), twh)
            full = Gate.build("iou", view, 0.7, size_weight=size_w).matrix(dxy, dwh)
            by_matrix = associate(cx, S, full, twh, dxy, dwh, dclass, 0.7, size_w,
                                  RULE_CODES[rule], NO_STAND, BY_MATRIX)
            by_overlap = associate(cx, S, np.zeros((0, 0)), twh, dxy, dwh, dclass, 0.7,
                                   size_w, RULE_CODES[rule], NO_STAND, BY_OVERLAP)
            np.testing.assert_array_equal(by_overlap, by_matrix)
            assert (by_overlap >= 0).sum() > n // 4


def test_the_gate_searches_each_distance_its_way() -> None:
    rng = np.random.default_rng(14)
    cx, twh, dxy, dwh = _boxes(rng, 120, 100, 2.0)
    view = TrackView(cx, np.broadcast_to(4 * np.eye(2), (120, 2, 2)),
                     np.broadcast_to(9 * np.eye(2), (120, 2, 2)), rng.normal(0, 2, (120, 2)),
                     twh)
    for distance, g in (("iou", 0.7), ("coupled-literal", 9.21), ("mahalanobis", 9.21)):
        gate = Gate.build(distance, view, g)
        full = gate.matrix(dxy, dwh)
        ti, dj, value = gate.pairs(dxy, dwh)
        rt, rd = np.nonzero(full <= g)
        np.testing.assert_array_equal(ti, rt)
        np.testing.assert_array_equal(dj, rd)
        np.testing.assert_allclose(value, full[rt, rd], rtol=1e-9)
        assert gate.dense(dxy, dwh).shape == ((120, 100) if distance == "coupled-literal"
                                               else (0, 0))
    # frame_pairs with the matrix search takes the values it is given
    cost = np.full((3, 2), 5.0)
    cost[1, 0] = 0.5
    ti, dj, c = frame_pairs(BY_MATRIX, np.zeros((3, 2)), np.zeros((3, 3)), cost,
                            np.ones((3, 2)), np.ones(3, bool), np.zeros((2, 2)),
                            np.ones((2, 2)), np.ones(2, bool), 1.0, 0.0)
    assert (ti.tolist(), dj.tolist(), c.tolist()) == ([1], [0], [0.5])
