"""X6 (coupled-gate) and X7 (crossing) experiments: headline figures and the simulation core."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association import ASSIGN_RULES, DISTANCES
from mvtrack.experiments import coupled_gate, crossing, crossing_measure, get
from mvtrack.experiments.report import write_report


def test_coupled_gate_reproduces_spec_x6(tmp_path) -> None:
    report = get("coupled-gate")(runs=None, seed=0)
    d = report.figures["distances"]
    assert set(d) == set(DISTANCES)
    np.testing.assert_allclose(d["euclidean"]["r2"], [32.0, 72.0])
    np.testing.assert_allclose(d["uncoupled"]["r2"], [32.0, 72.0])
    np.testing.assert_allclose(d["coupled"]["r2"], [20.0, 18.0])
    assert d["uncoupled"]["winner"] == 1 and d["coupled"]["winner"] == 2
    assert d["coupled"]["translation_invariant"]
    assert not d["coupled-literal"]["translation_invariant"]
    assert report.figures["paper"]["winner"]["coupled"] == 2
    paths = write_report(report, tmp_path)
    assert (tmp_path / "coupled-gate.json").exists()
    assert any(p.suffix == ".png" for p in paths)
    assert "| coupled | 20 / 18 | 20 / 18 | 2 | 2 | yes |" in report.markdown()


def test_coupled_gate_evaluate_is_shift_invariant_except_literal() -> None:
    a = coupled_gate.evaluate()
    b = coupled_gate.evaluate(np.array([1000.0, 500.0]))
    for name in DISTANCES:
        same = np.allclose(a[name]["r2"], b[name]["r2"])
        assert same == (name != "coupled-literal"), name


def _noise_free(runs: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    xy = crossing_measure.truth(runs, seed, 0.0)
    flip = np.random.default_rng(seed).random(xy.shape[:2]) < 0.5
    return xy, flip


@pytest.mark.parametrize("rule", ASSIGN_RULES)
def test_crossing_without_noise_never_swaps(rule: str) -> None:
    """Exact measurements: every track keeps its own target through the crossing."""
    z, flip = _noise_free(3, 1)
    for dist in ("euclidean", "coupled", "mahalanobis"):
        taken, est = crossing_measure.simulate(z, flip, dist, rule)
        # at frame 50 both targets are at (160, 120): the two measurements are identical
        # and the nearest rule may hand both tracks the same one
        keep = np.r_[2:50, 51:100]
        assert (taken[:, keep] == [0, 1]).all(), (dist, rule)
        np.testing.assert_allclose(est[:, 60:], z[:, 60:], atol=1e-6)


def test_crossing_truth_meets_at_frame_50() -> None:
    for jitter in (0.0, 0.25):
        xy = crossing_measure.truth(2, 3, jitter)
        np.testing.assert_allclose(xy[:, 50], [[[160.0, 120.0]] * 2] * 2, atol=1e-9)
    xy = crossing_measure.truth(2, 3, 0.0)
    np.testing.assert_allclose(xy[:, 0], [[[20.0, 220.0], [20.0, 120.0]]] * 2, atol=1e-9)
    np.testing.assert_allclose(xy[:, 1] - xy[:, 0], [[[2.8, -2.0], [2.8, 0.0]]] * 2, atol=1e-9)


def test_crossing_runs_are_independent_in_the_batch() -> None:
    rng = np.random.default_rng(5)
    z, flip = crossing_measure.measurements(crossing_measure.truth(4, 5, 0.25), rng)
    for dist, rule in (("coupled", "nearest"), ("uncoupled", "optimal"), ("iou", "greedy")):
        batch, _ = crossing_measure.simulate(z, flip, dist, rule)
        for i in (0, 3):
            alone, _ = crossing_measure.simulate(z[i : i + 1], flip[i : i + 1], dist, rule)
            np.testing.assert_array_equal(batch[i], alone[0])


def test_crossing_swap_is_the_majority_of_the_last_frames() -> None:
    taken = np.zeros((3, 100, 2), dtype=np.intp)
    taken[1, -11:, 0] = 1  # 11 of the last 20 frames on target 2: a swap
    taken[2, -10:, 0] = 1  # 10 of 20: not a majority
    assert crossing_measure._swaps(taken).tolist() == [False, True, False]


def test_crossing_report_keys_and_ranges() -> None:
    report = get("crossing")(runs=3, seed=2)
    f = report.figures
    for key in ("swap_rate", "swap_rate_jitter", "failure_rate", "merge_rate"):
        assert set(f[key]) == set(DISTANCES)
        for dist in DISTANCES:
            assert set(f[key][dist]) == set(ASSIGN_RULES)
            assert all(v in (0.0, 1 / 3, 2 / 3, 1.0) for v in f[key][dist].values())
    for dist in DISTANCES:  # a swap of track 1 is a failure
        for rule in ASSIGN_RULES:
            assert f["failure_rate"][dist][rule] >= f["swap_rate"][dist][rule]
    assert f["runs"] == 3 and "paper" in f
    # ρ = 1 with equal per-axis variances is eq. (9): the same choices, the same rates
    assert f["coupled_rho_sweep"]["1"] == f["swap_rate"]["uncoupled"]
    assert f["coupled_rho_sweep_jitter"]["1"] == f["swap_rate_jitter"]["uncoupled"]
    assert set(f["coupled_rho_sweep"]) == {"1", "1.5", "3", "4"}
    assert set(report.plots) == {"trajectories", "swap_rates"}
    with pytest.raises(ValueError, match="runs"):
        crossing.run(runs=0, seed=0)
