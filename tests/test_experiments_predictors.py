"""X1 (paper 1 Figs. 5–8): the trajectory, the batched error computation and the report."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtrack.experiments import predictors as x1
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
    report = x1.run(runs=12, seed=3)
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
    assert (tmp_path / "predictors_fig8_ensemble_mse.png").stat().st_size > 1000
    assert (tmp_path / "predictors.md").read_text().startswith("# X1")
    assert len(paths) == 2 + len(report.plots)


def test_same_seed_same_result_and_runs_validated() -> None:
    a = x1.run(runs=2, seed=5).figures
    b = x1.run(runs=2, seed=5).figures
    assert a["kf_mse_windows"] == b["kf_mse_windows"]
    with pytest.raises(ValueError, match="runs"):
        x1.run(runs=0)
