"""Score calibration and duplicate suppression (mvtrack.tracking.scores), by hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.eval.iou import iou_matrix
from mvtrack.tracking.scores import (
    DENSE_OVERLAP,
    ScoreCalibration,
    check_scale,
    duplicates,
    isolated,
)


def test_auto_is_the_empirical_distribution_of_the_run_so_far():
    cal = ScoreCalibration("auto")
    # frame 1: four scores; c = #{s_j <= s} / 4
    assert cal([5.0, -1.0, 20.0, 2.0]).tolist() == [0.75, 0.25, 1.0, 0.5]
    # frame 2 adds two: the six scores seen are -1, 2, 3, 5, 20, 100
    assert cal([100.0, 3.0]).tolist() == [6 / 6, 3 / 6]
    # ties count as "<="
    cal2 = ScoreCalibration("auto")
    assert cal2([1.0, 1.0, 1.0]).tolist() == [1.0, 1.0, 1.0]


def test_auto_depends_only_on_the_order_of_the_scores():
    rng = np.random.default_rng(0)
    frames = [rng.normal(size=rng.integers(0, 6)) for _ in range(30)]
    a, b = ScoreCalibration("auto"), ScoreCalibration("auto")
    for s in frames:
        np.testing.assert_array_equal(a(s), b(np.exp(3 * s) + 7))


def test_prime_fixes_the_calibration():
    cal = ScoreCalibration("auto")
    cal.prime([0.0, 1.0, 2.0, 3.0])
    assert cal([1.5, 3.0, -5.0]).tolist() == [0.5, 1.0, 0.0]
    assert cal([1.5]).tolist() == [0.5]  # primed: the frames do not change it
    cal.reset()
    assert cal([1.5]).tolist() == [1.0]


def test_capacity_keeps_every_second_score():
    cal = ScoreCalibration("auto", capacity=8, batch=1)
    cal(np.arange(9.0))  # 9 > 8: the sorted 0..8 thinned to 1, 3, 5, 7
    assert cal._sorted.tolist() == [1.0, 3.0, 5.0, 7.0]
    assert cal([4.0]).tolist() == [3 / 5]  # 4 joined: 1, 3, 4, 5, 7


def test_prob_and_linear_scales():
    assert ScoreCalibration("prob")([-0.5, 0.3, 1.7]).tolist() == [0.0, 0.3, 1.0]
    np.testing.assert_allclose(ScoreCalibration((-1.0, 3.0))([-2.0, 0.0, 2.0, 9.0]),
                               [0.0, 0.25, 0.75, 1.0])


@pytest.mark.parametrize("bad", ["rank", (3.0, 1.0), (0.0, float("inf")), (1.0,), 5])
def test_bad_scales_are_refused(bad):
    with pytest.raises(ValueError, match="score scale"):
        check_scale(bad)


def test_duplicates_greedy_suppression_by_hand():
    # boxes (centre, size): A and B overlap by IoU 0.6, B and C by 0.6, A and C not at all
    xy = np.array([[10.0, 10.0], [12.5, 10.0], [15.0, 10.0], [100.0, 100.0]])
    wh = np.full((4, 2), 10.0)
    # IoU of two 10x10 boxes shifted by 2.5 px: 75 / 125 = 0.6
    dup = duplicates(xy, wh, np.array([3.0, 2.0, 1.0, 0.5]), 0.5)
    assert dup.tolist() == [False, True, False, False]  # B goes; C stays (A is not over it)
    # B best: it suppresses both neighbours
    dup = duplicates(xy, wh, np.array([2.0, 3.0, 1.0, 0.5]), 0.5)
    assert dup.tolist() == [True, False, True, False]
    # equal scores: the leftmost box of a pair is kept, whatever the order of the rows
    for perm in ([0, 1, 2, 3], [2, 1, 0, 3], [3, 2, 1, 0]):
        dup = duplicates(xy[perm], wh[perm], np.ones(4), 0.5)
        assert dup[np.argsort(perm)].tolist() == [False, True, False, False]
    # above the threshold nothing is a duplicate
    assert not duplicates(xy, wh, np.array([3.0, 2.0, 1.0, 0.5]), 0.61).any()


def test_isolated_boxes_by_hand():
    # candidates A, B (IoU 0.6 with each other), C; D far away; one other box over C
    xy = np.array([[10.0, 10.0], [12.5, 10.0], [50.0, 50.0], [100.0, 100.0]])
    wh = np.full((4, 2), 10.0)
    oxy, owh = np.array([[52.5, 50.0]]), np.array([[10.0, 10.0]])  # IoU 0.6 with C
    score = np.array([1.0, 2.0, 3.0, 4.0])
    # C overlaps a track; of A and B, the better-scored B stays; D is alone
    assert isolated(xy, wh, score, oxy, owh, 0.5).tolist() == [False, True, False, True]
    # a threshold above every overlap: all of them (A and B no longer duplicates either)
    assert isolated(xy, wh, score, oxy, owh, 0.61).all()
    # exactly at the threshold counts as overlapping (IoU >= t)
    assert isolated(xy, wh, score, oxy, owh, 0.6).tolist() == [False, True, False, True]
    # B under a second box (centre (15, 10): IoU 0.6 with B, 1/3 with A): B goes, and A,
    # which only B suppressed, stays
    oxy2, owh2 = np.array([[52.5, 50.0], [15.0, 10.0]]), np.full((2, 2), 10.0)
    assert isolated(xy, wh, score, oxy2, owh2, 0.5).tolist() == [True, False, False, True]
    # boxes of other sizes: a 20 x 20 box holding D (IoU 100 / 400 = 0.25)
    oxy3, owh3 = np.array([[100.0, 100.0]]), np.array([[20.0, 20.0]])
    assert isolated(xy[3:], wh[3:], score[3:], oxy3, owh3, 0.25).tolist() == [False]
    assert isolated(xy[3:], wh[3:], score[3:], oxy3, owh3, 0.26).tolist() == [True]
    # nothing to compare with: every box, less the duplicates
    none = np.zeros((0, 2))
    assert isolated(xy, wh, score, none, none, 0.5).tolist() == [False, True, True, True]


@pytest.mark.parametrize("m", [20, 400])  # the dense test, and the spatial grid's pairs
def test_isolated_equals_the_iou_matrix(m):
    rng = np.random.default_rng(m)
    k = 300
    xy, oxy = rng.uniform(0, 2000, (m, 2)), rng.uniform(0, 2000, (k, 2))
    wh, owh = rng.uniform(10, 120, (m, 2)), rng.uniform(10, 120, (k, 2))
    assert (m * k > DENSE_OVERLAP) == (m == 400)
    score = rng.permutation(m).astype(float)
    for t in (0.05, 0.3):
        tl = np.concatenate([xy - wh / 2, wh], axis=1)
        otl = np.concatenate([oxy - owh / 2, owh], axis=1)
        alone = iou_matrix(tl, otl).max(axis=1) < t
        dup = np.zeros(m, bool)
        idx = alone.nonzero()[0]
        dup[idx] = duplicates(xy[idx], wh[idx], score[idx], t)
        got = isolated(xy, wh, score, oxy, owh, t)
        np.testing.assert_array_equal(got, alone & ~dup)
        assert 0 < got.sum() < m  # both kinds of boxes occur


def test_pending_scores_give_the_same_calibration_as_one_sorted_sample():
    rng = np.random.default_rng(1)
    frames = [rng.normal(size=rng.integers(0, 9)) for _ in range(200)]
    batched, direct = ScoreCalibration("auto", batch=16), ScoreCalibration("auto", batch=0)
    seen = np.zeros(0)
    for s in frames:
        seen = np.concatenate([seen, s])
        ref = np.searchsorted(np.sort(seen), s, side="right") / max(seen.size, 1)
        np.testing.assert_allclose(batched(s), ref, rtol=0, atol=1e-15)
        np.testing.assert_allclose(direct(s), ref, rtol=0, atol=1e-15)
