"""X3 (paper 1 Table 2): the timed implementations compute the right thing; report keys."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.experiments import predictors_measure as x1
from mvtrack.experiments import timing as x3
from mvtrack.filters import rls


def _library_kf_prediction(y: np.ndarray) -> float:
    e = x1.kf_errors(np.concatenate([y, [0.0]])[None, :], np.zeros(len(y) + 1))
    return float(e[0, -1])  # prediction of sample len(y) from y


def _library_rls_prediction(y: np.ndarray) -> float:
    s = rls.init(1, 3, 100.0)
    for v in y:
        s, _ = rls.update(s, np.array([v]), 0.98)
    return float(rls.predict(s)[0])


def test_timed_implementations_equal_the_library() -> None:
    y = x3.measurements(400)
    kf_ref = _library_kf_prediction(y)
    rls_ref = _library_rls_prediction(y)
    assert x3.python_kf(y.tolist()) == pytest.approx(kf_ref, rel=1e-9)
    assert x3.numpy_kf(y) == pytest.approx(kf_ref, rel=1e-9)
    assert x3.python_rls(y.tolist()) == pytest.approx(rls_ref, rel=1e-9)
    assert x3.numpy_rls(y) == pytest.approx(rls_ref, rel=1e-9)


def test_measurements_repeat_the_x1_run() -> None:
    y = x3.measurements(800, seed=2)
    np.testing.assert_array_equal(y[360:720], y[:360])


def test_report_rows_and_ratios(monkeypatch) -> None:
    monkeypatch.setattr(x3, "ITERATIONS", [100, 200])
    monkeypatch.setattr(x3, "BATCH", 300)
    monkeypatch.setattr(x3, "PAPER_MS", {"kf": [5.86, 13.1], "rls": [0.42, 1.78]})
    report = x3.run(runs=1, seed=0)
    rows = report.figures["rows"]
    assert [r["iterations"] for r in rows] == [100, 200]
    for r in rows:
        for key in ("python_kf_ms", "python_rls_ms", "numpy_kf_ms", "numpy_rls_ms"):
            assert r[key] > 0
        assert r["python_ratio"] == pytest.approx(r["python_rls_ms"] / r["python_kf_ms"])
        assert r["paper_ratio"] == pytest.approx(r["paper_rls_ms"] / r["paper_kf_ms"])
    assert set(report.figures["batched_ns_per_target"]) == {"kf", "rls"}
    with pytest.raises(ValueError, match="runs"):
        x3.run(runs=0)
