"""Score calibration (mvtrack.tracking.scores), by hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking.scores import ScoreCalibration, check_scale


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
