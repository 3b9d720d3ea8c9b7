"""X1: paper 1's 1-D predictor comparison, KF vs RLS (Figs. 5–8, SPEC §5 X1).

A vehicle on one axis cruises at 50 km/h, brakes into an intersection, makes a 180° turn
without stopping (a 1-D velocity reversal) and leaves (SPEC X1 table; Δt = 1/30 s, 360
samples). Noisy positions ``y_k = p_k + N(0, 5)`` feed a constant-acceleration KF
(eqs. 8–9, q = 0.5, R = 5, x̄₀ = 0, P̄₀ = 100 I) and the RLS predictor (M = 3, λ = 0.98,
ŵ₀ = 0, P₀ = 100 I). Both see the same noise in each of the Monte-Carlo runs, which are run
as one batch (one filter per run). Measured: the one-step prediction errors
``H x̄_k − p_k`` and ``ŵ_{k−1}ᵀ ỹ_k − p_k``, their ensemble mean square per k (Fig. 8) and
its means over the SPEC windows; plus a sweep of the forgetting factor λ.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments.report import Report
from mvtrack.filters import kalman, rls
from mvtrack.filters.base import FloatArray
from mvtrack.filters.models import constant_acceleration

DT = 1.0 / 30.0
N_SAMPLES = 360
V0 = 13.889  # 50 km/h in m/s
#: (start s, end s, acceleration m/s²) of SPEC X1
PHASES = [(0.0, 2.0, 0.0), (2.0, 5.0, -2.963), (5.0, 7.0, -5.0), (7.0, 10.0, -2.963),
          (10.0, 12.0, 0.0)]
NOISE_VAR = 5.0
KF_Q = 0.5
P0 = 100.0
RLS_M = 3
RLS_LAMBDA = 0.98
LAMBDAS = [0.9, 0.95, 0.98, 1.0]
#: SPEC X1 windows of k, half-open [a, b)
WINDOWS = [(1, 30), (30, 60), (60, 150), (150, 210), (210, 300), (300, 360)]
DEFAULT_RUNS = 100

PAPER = {
    "claims": [
        "Fig. 7: RLS is in error until its coefficients converge, and errs and oscillates "
        "whenever the acceleration changes; the KF changes little.",
        "Fig. 8: the KF has a large initial error from its initial state, then stays smooth "
        "with a short deviation at large accelerations and quick recovery; it removes most "
        "of the noise.",
        "Fig. 8: RLS has a large initial error, larger variation, and oscillates until it "
        "re-converges.",
        "Overall tracking ability is similar.",
    ],
    "spec_prototype": {
        "kf_first_30": 1.6,
        "kf_after": 0.6,
        "rls_first_30": 88.0,
        "rls_after": [2.0, 2.8],
    },
}


def trajectory() -> tuple[FloatArray, FloatArray, FloatArray]:
    """True position, velocity and acceleration at k = 0…359 (SPEC X1), integrated exactly.

    The acceleration is piecewise constant over each sample interval [kΔt, (k+1)Δt).
    """
    t = np.arange(N_SAMPLES) * DT
    acc = np.zeros(N_SAMPLES)
    for a, b, value in PHASES:
        acc[(t >= a - 1e-9) & (t < b - 1e-9)] = value
    p = np.zeros(N_SAMPLES)
    v = np.zeros(N_SAMPLES)
    v[0] = V0
    for k in range(N_SAMPLES - 1):
        p[k + 1] = p[k] + v[k] * DT + 0.5 * acc[k] * DT * DT
        v[k + 1] = v[k] + acc[k] * DT
    return p, v, acc


def kf_errors(y: FloatArray, p: FloatArray, q: float = KF_Q) -> FloatArray:
    """One-step KF prediction errors ``H x̄_k − p_k`` (runs, K) for measurements y (runs, K)."""
    runs, K = y.shape
    model = constant_acceleration(DT, q, NOISE_VAR)
    x = np.zeros((runs, 3))
    P = np.broadcast_to(np.eye(3) * P0, (runs, 3, 3)).copy()
    err = np.empty((runs, K))
    for k in range(K):
        err[:, k] = x[:, 0] - p[k]  # x̄_k, P̄_k: the prediction before y_k
        x, P = kalman.update(x, P, y[:, k : k + 1], model.H, model.R)
        x, P = kalman.predict(x, P, model.F, model.Q)
    return err


def rls_errors(y: FloatArray, p: FloatArray, lam: float = RLS_LAMBDA, M: int = RLS_M
               ) -> FloatArray:
    """One-step RLS prediction errors ``ŵ_{k−1}ᵀ ỹ_k − p_k`` (runs, K), E1.5."""
    runs, K = y.shape
    state = rls.init(runs, M, P0)
    err = np.empty((runs, K))
    for k in range(K):
        err[:, k] = rls.predict(state) - p[k]
        state, _ = rls.update(state, y[:, k], lam, c=P0)
    return err


def window_means(curve: FloatArray) -> list[float]:
    """Means of ``curve`` (per k) over the SPEC windows, in order."""
    return [float(curve[a:b].mean()) for a, b in WINDOWS]


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Run X1 with ``runs`` Monte-Carlo runs (default 100) from ``seed``."""
    runs = DEFAULT_RUNS if runs is None else int(runs)
    if runs < 1:
        raise ValueError(f"runs must be at least 1, got {runs}")
    rng = np.random.default_rng(seed)
    p, _, acc = trajectory()
    y = p + rng.normal(0.0, np.sqrt(NOISE_VAR), size=(runs, N_SAMPLES))  # same noise for both
    e_kf = kf_errors(y, p)
    e_rls = rls_errors(y, p)
    mse_kf = (e_kf**2).mean(axis=0)
    mse_rls = (e_rls**2).mean(axis=0)
    sweep: dict[str, Any] = {}
    for lam in LAMBDAS:
        curve = (rls_errors(y, p, lam) ** 2).mean(axis=0)
        sweep[str(lam)] = {"mse_windows": window_means(curve), "mse": float(curve[1:].mean())}

    kf_w, rls_w = window_means(mse_kf), window_means(mse_rls)
    after = slice(60, N_SAMPLES)
    changes = np.zeros(N_SAMPLES, bool)  # 20 samples after each change of acceleration
    for c in (60, 150, 210, 300):
        changes[c : c + 20] = True
    steady = ~changes
    steady[:60] = False
    checks = {
        "kf_initial_error_large": bool(mse_kf[1:30].mean() > 2 * mse_kf[after].mean()),
        "kf_rises_at_acceleration_changes": bool(
            mse_kf[changes].mean() > 1.1 * mse_kf[steady].mean()),
        "rls_rises_at_acceleration_changes": bool(
            mse_rls[changes].mean() > 1.1 * mse_rls[steady].mean()),
        "kf_removes_most_noise": bool(np.median(mse_kf[after]) < NOISE_VAR / 2),
        "rls_initial_error_large": bool(mse_rls[1:30].mean() > 5 * np.median(mse_rls[after])),
        "rls_varies_more_than_kf": bool(np.std(mse_rls[after]) > np.std(mse_kf[after])),
        "rls_mse_above_kf_after_warmup": bool(mse_rls[after].mean() > mse_kf[after].mean()),
    }
    figures: dict[str, Any] = {
        "runs": runs,
        "seed": seed,
        "windows": [list(w) for w in WINDOWS],
        "kf_mse_windows": kf_w,
        "rls_mse_windows": rls_w,
        "kf_mse": float(mse_kf[1:].mean()),
        "rls_mse": float(mse_rls[1:].mean()),
        "kf_mse_curve": mse_kf.tolist(),
        "rls_mse_curve": mse_rls.tolist(),
        "lambda_sweep": sweep,
        "noise_variance": NOISE_VAR,
        "definitions": {
            "error": "one-step prediction error: H x̄_k − p_k (KF), ŵ_{k−1}ᵀ ỹ_k − p_k (RLS)",
            "mse_curve": "ensemble mean over runs of the squared error, per k = 0…359",
            "mse_windows": "mean of the curve over each window [a, b) of k, in order",
            "mse": "mean of the curve over k = 1…359",
        },
        "checks": checks,
        "paper": PAPER,
        "setup": {"dt": DT, "samples": N_SAMPLES, "kf_q": KF_Q, "kf_R": NOISE_VAR,
                  "kf_P0": P0, "rls_M": RLS_M, "rls_lambda": RLS_LAMBDA, "rls_c": P0},
    }
    proto = PAPER["spec_prototype"]
    rows: list[list[Any]] = []
    for (a, b), kf_v, rls_v in zip(WINDOWS, kf_w, rls_w, strict=True):
        first = a == 1
        rows.append([
            f"[{a}, {b})",
            proto["kf_first_30"] if first else proto["kf_after"],
            kf_v,
            proto["rls_first_30"] if first else "2.0–2.8",
            rls_v,
        ])
    rows.append(["all k ≥ 1", "—", figures["kf_mse"], "—", figures["rls_mse"]])
    for lam in LAMBDAS:
        s = sweep[str(lam)]
        rows.append([f"RLS λ = {lam}, all k ≥ 1", "—", "—", "—", s["mse"]])
    notes = _notes(figures)
    return Report(
        name="predictors",
        title="X1 — paper 1 Figs. 5–8: KF vs RLS one-step prediction error (m²)",
        figures=figures,
        columns=["window of k", "SPEC prototype KF", "ours KF", "SPEC prototype RLS",
                 "ours RLS"],
        rows=rows,
        notes=notes,
        plots=_plots(p, acc, y, e_kf, e_rls, mse_kf, mse_rls, sweep),
    )


def _notes(fig: dict[str, Any]) -> str:
    c = fig["checks"]
    yes = {True: "yes", False: "**no**"}
    lines = [
        f"{fig['runs']} Monte-Carlo runs (seed {fig['seed']}), the same measurement noise "
        "(variance 5 m²) for both predictors; ensemble mean squared one-step prediction "
        "error averaged over each window of k. The paper gives curves only (Figs. 7–8); the "
        "'prototype' columns are the values SPEC X1 reports from a prototype.",
        "",
        "Paper's qualitative claims, checked on our curves:",
        "",
        f"- KF has a large initial error (window [1, 30) above twice its mean after k = 60): "
        f"{yes[c['kf_initial_error_large']]}. Note x̄₀ = 0 equals the true start p₀ = 0; the "
        "initial error comes from the unknown velocity (50 km/h against x̄₀'s 0).",
        f"- KF error rises after the acceleration changes (k = 60, 150, 210, 300; 20 samples "
        f"each, against the rest after k = 60, by > 10 %): "
        f"{yes[c['kf_rises_at_acceleration_changes']]}.",
        f"- RLS error rises after the acceleration changes: "
        f"{yes[c['rls_rises_at_acceleration_changes']]}.",
        f"- KF removes most of the noise (median MSE after k = 60 below half the noise "
        f"variance): {yes[c['kf_removes_most_noise']]}.",
        f"- RLS has a large initial error until it converges: "
        f"{yes[c['rls_initial_error_large']]}.",
        f"- RLS varies more than the KF after warm-up: {yes[c['rls_varies_more_than_kf']]}.",
        f"- RLS error above the KF's after warm-up (the paper calls overall tracking "
        f"ability similar): {yes[c['rls_mse_above_kf_after_warmup']]}.",
    ]
    return "\n".join(lines)


def _plots(p, acc, y, e_kf, e_rls, mse_kf, mse_rls, sweep) -> dict[str, Any]:
    from matplotlib.figure import Figure

    t = np.arange(N_SAMPLES) * DT
    k = np.arange(N_SAMPLES)
    plots: dict[str, Any] = {}
    fig = Figure(figsize=(7, 3.5))
    ax = fig.subplots()
    ax.plot(t, y[0], ".", ms=2, color="0.6", label="measurements (run 0)")
    ax.plot(t, p, "k-", label="true position")
    ax.set(xlabel="time (s)", ylabel="position (m)", title="Fig. 5: trajectory")
    ax.legend()
    plots["fig5_trajectory"] = fig

    fig = Figure(figsize=(7, 3))
    ax = fig.subplots()
    ax.step(t, acc, where="post", color="k")
    ax.set(xlabel="time (s)", ylabel="acceleration (m/s²)", title="Fig. 6: acceleration")
    plots["fig6_acceleration"] = fig

    fig = Figure(figsize=(7, 3.5))
    ax = fig.subplots()
    ax.plot(k, e_rls[0], label="RLS", lw=1)
    ax.plot(k, e_kf[0], label="KF", lw=1)
    ax.set(xlabel="k", ylabel="prediction error (m)", ylim=(-15, 15),
           title="Fig. 7: one run, one-step prediction error")
    ax.legend()
    plots["fig7_one_run"] = fig

    fig = Figure(figsize=(7, 3.5))
    ax = fig.subplots()
    ax.semilogy(k[1:], mse_rls[1:], label="RLS λ = 0.98", lw=1)
    ax.semilogy(k[1:], mse_kf[1:], label="KF", lw=1)
    ax.axhline(NOISE_VAR, color="0.5", ls=":", label="noise variance")
    ax.set(xlabel="k", ylabel="ensemble MSE (m²)", title="Fig. 8: ensemble mean squared error")
    ax.legend()
    plots["fig8_ensemble_mse"] = fig

    fig = Figure(figsize=(7, 3.5))
    ax = fig.subplots()
    centres = [0.5 * (a + b) for a, b in WINDOWS]
    for lam, s in sweep.items():
        ax.semilogy(centres, s["mse_windows"], "o-", label=f"RLS λ = {lam}")
    ax.semilogy(centres, window_means(mse_kf), "ks--", label="KF")
    ax.set(xlabel="window centre k", ylabel="window MSE (m²)", title="λ sweep")
    ax.legend()
    plots["lambda_sweep"] = fig
    return plots
