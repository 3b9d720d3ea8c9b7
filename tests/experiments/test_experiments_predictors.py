"""X1 (paper 1 Figs. 5–8): the trajectory, the batched error computation and the report."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from mvtrack.experiments import predictors
from mvtrack.experiments import predictors_measure as x1
from mvtrack.experiments.report import write_report
from mvtrack.filters import kalman
from mvtrack.filters.models import constant_acceleration


def test_trajectory_matches_spec_landmarks() -> None:
    p, v, acc = x1.trajectory()
    assert p.shape == (360,)
    assert p[0] == 0.0 and v[0] == pytest.approx(13.889)
    assert np.argmax(p) == pytest.approx(180, abs=1)  # peak at t = 6 s
    assert p.max() == pytest.approx(58.6, abs=0.1)
    assert v[150] == pytest.approx(5.0, abs=1e-2)  # after braking (t = 5 s)
    assert v[210] == pytest.approx(-5.0, abs=1e-2)  # after the turn
    assert v[-1] == pytest.approx(-13.889, abs=1e-2)
    assert abs(p[-1]) < 3.0  # returns to about 0
    np.testing.assert_allclose(np.unique(acc), [-5.0, -2.963, 0.0])


def test_batched_kf_errors_equal_one_run_at_a_time() -> None:
    p, _, _ = x1.trajectory()
    rng = np.random.default_rng(1)
    y = p + rng.normal(0, np.sqrt(5), size=(3, 360))
    e = x1.kf_errors(y, p)
    model = constant_acceleration(x1.DT, 0.5, 5.0)
    x, P = np.zeros((1, 3)), 100.0 * np.eye(3)[None]
    for k in range(360):
        assert e[2, k] == pytest.approx(x[0, 0] - p[k], rel=1e-12, abs=1e-12)
        x, P = kalman.update(x, P, y[2:3, k : k + 1], model.H, model.R)
        x, P = kalman.predict(x, P, model.F, model.Q)


def test_rls_error_at_k_is_prediction_from_earlier_samples() -> None:
    p, _, _ = x1.trajectory()
    y = np.tile(p, (2, 1))
    y[1, 100:] += 1000.0  # a future change must not affect earlier predictions
    e = x1.rls_errors(y, p)
    np.testing.assert_array_equal(e[0, :101], e[1, :101])
    assert e[0, 0] == -p[0]  # ŵ₀ = 0 predicts 0


def test_report_has_keys_and_sane_values(tmp_path) -> None:
    report = predictors.run(runs=12, seed=3)
    fig = report.figures
    for key in ("kf_mse_windows", "rls_mse_windows", "kf_mse", "rls_mse", "lambda_sweep",
                "paper", "windows"):
        assert key in fig
    assert fig["windows"] == [list(w) for w in x1.WINDOWS]
    assert len(fig["kf_mse_windows"]) == len(x1.WINDOWS) == len(fig["rls_mse_windows"])
    # after warm-up the KF removes most of the noise (variance 5), RLS converges below it
    assert max(fig["kf_mse_windows"][2:]) < 5.0 / 2
    assert max(fig["rls_mse_windows"][2:]) < 5.0
    # RLS starts from ŵ = 0: a large initial error
    assert fig["rls_mse_windows"][0] > 10 * fig["rls_mse_windows"][-1]
    assert set(fig["lambda_sweep"]) == {"0.9", "0.95", "0.98", "1.0"}
    assert fig["lambda_sweep"]["0.98"]["mse_windows"] == pytest.approx(fig["rls_mse_windows"])
    paths = write_report(report, tmp_path)
    data = json.loads((tmp_path / "predictors.json").read_text())
    assert data["kf_mse"] == pytest.approx(fig["kf_mse"])
    img = cv2.imread(str(tmp_path / "predictors_fig8_ensemble_mse.png"))
    assert img is not None and img.ndim == 3
    # the KF and RLS curves are drawn in colour (the axes, labels and background are grey)
    assert np.count_nonzero(img.max(axis=2).astype(int) - img.min(axis=2) > 60) > 200
    assert (tmp_path / "predictors.md").read_text().startswith("# X1")
    assert len(paths) == 2 + len(report.plots)


def test_same_seed_same_result_and_runs_validated() -> None:
    a = predictors.run(runs=2, seed=5).figures
    b = predictors.run(runs=2, seed=5).figures
    assert a["kf_mse_windows"] == b["kf_mse_windows"]
    with pytest.raises(ValueError, match="runs"):
        predictors.run(runs=0)


def test_oscillation_measure_detects_alternation_only_after_the_changes() -> None:
    rng = np.random.default_rng(0)
    runs, K = 200, 360
    smooth = np.cumsum(rng.normal(0, 1, (runs, K)), axis=1)  # random walk: few sign changes
    o = x1.oscillation(smooth)
    assert o["sign_changes"]["pre"] < 0.2 and not o["more_after_changes"]
    white = rng.normal(0, 1, (runs, K))
    o = x1.oscillation(white)
    assert o["sign_changes"]["pre"] == pytest.approx(0.5, abs=0.02)
    assert o["hf_share"]["pre"] == pytest.approx(0.5, abs=0.05)
    assert not o["more_after_changes"] and abs(o["sign_changes"]["z"]) < 4
    ringing = smooth.copy()
    for c in x1.CHANGES:  # a decaying alternation for 30 samples after each change
        n = np.arange(30)
        ringing[:, c : c + 30] = 50 * (-1.0) ** n * np.exp(-n / 15) + white[:, c : c + 30]
    o = x1.oscillation(ringing)
    assert o["more_after_changes"] and o["rings"]
    assert o["sign_changes"]["post"] > 0.9 and o["sign_changes"]["z"] > 10
    lo, hi = o["sign_changes"]["post_ci95"]
    assert lo <= o["sign_changes"]["post"] <= hi and hi - lo < 0.02


def test_rls_weights_average_the_last_three_samples_and_oscillate_more_than_the_kf() -> None:
    report = predictors.run(runs=30, seed=1)
    fig = report.figures
    sw = fig["lambda_sweep"]["0.98"]
    w = np.array(sw["mean_weights_after_warmup"])
    np.testing.assert_allclose(w, 1 / 3, atol=0.06)  # a moving average, not (3, −3, 1)
    assert w.sum() == pytest.approx(1.0, abs=0.03)
    # the noise the taps pass is at least R / M (the minimum of R Σw² under Σw = 1)
    assert 5.0 * sw["noise_gain_after_warmup"] >= fig["rls_noise_floor"] - 1e-9
    assert fig["rls_mse_after_warmup"] > 2.5 * fig["kf_mse_after_warmup"]
    assert fig["checks"]["rls_oscillates_more_than_kf"]
    # the oscillation is there all the time, not brought on by the acceleration changes
    assert not fig["checks"]["rls_oscillates_more_after_acceleration_changes"]
    rates = [fig["lambda_sweep"][str(lam)]["oscillation"]["sign_changes"]["pre"]
             for lam in x1.LAMBDAS]
    assert rates == sorted(rates, reverse=True)  # shorter memory, more oscillation
    # the oscillation figure shows these numbers, each bar with its 95 % interval
    ax = report.plots["oscillation"].axes[0]
    bars = {c.get_label(): [p.get_height() for p in c.patches] for c in ax.containers
            if hasattr(c, "patches") and not c.get_label().startswith("_")}
    before = bars["30 samples before each change"]
    assert before[1:] == pytest.approx(rates)
    assert before[0] == pytest.approx(fig["kf_oscillation"]["sign_changes"]["pre"])
    segs = [seg for coll in ax.collections for seg in coll.get_segments()]
    assert len(segs) >= 2 * len(before)
    # Fig. 8 draws the R / M floor that any 3-tap average passes
    fig8 = report.plots["fig8_ensemble_mse"].axes[0]
    floors = [line for line in fig8.lines if line.get_label().startswith("R / M")]
    assert floors and floors[0].get_ydata()[0] == pytest.approx(5.0 / 3)
