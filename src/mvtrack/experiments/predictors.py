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

from mvtrack.experiments.predictors_measure import (
    CHANGES,
    DT,
    KF_Q,
    LAMBDAS,
    N_SAMPLES,
    NOISE_VAR,
    P0,
    RLS_LAMBDA,
    RLS_M,
    WINDOWS,
    kf_errors,
    oscillation,
    rls_run,
    trajectory,
    window_means,
)
from mvtrack.experiments.predictors_report import report_notes, report_plots
from mvtrack.experiments.report import Report
from mvtrack.filters.base import FloatArray

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


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Run X1 with ``runs`` Monte-Carlo runs (default 100) from ``seed``."""
    runs = DEFAULT_RUNS if runs is None else int(runs)
    if runs < 1:
        raise ValueError(f"runs must be at least 1, got {runs}")
    rng = np.random.default_rng(seed)
    p, _, acc = trajectory()
    y = p + rng.normal(0.0, np.sqrt(NOISE_VAR), size=(runs, N_SAMPLES))  # same noise for both
    e_kf = kf_errors(y, p)
    mse_kf = (e_kf**2).mean(axis=0)
    after = slice(60, N_SAMPLES)
    sweep: dict[str, Any] = {}
    errs: dict[str, FloatArray] = {}
    for lam in LAMBDAS:
        e, w = rls_run(y, p, lam)
        errs[str(lam)] = e
        curve = (e**2).mean(axis=0)
        w2 = (w[:, after] ** 2).sum(axis=-1)
        sweep[str(lam)] = {
            "mse_windows": window_means(curve),
            "mse": float(curve[1:].mean()),
            "mse_after_warmup": float(curve[after].mean()),
            "mean_weights_after_warmup": w[:, after].mean(axis=(0, 1)).tolist(),
            "noise_gain_after_warmup": float(w2.mean()),  # E‖ŵ‖²: R E‖ŵ‖² is the noise part
            "oscillation": oscillation(e),
        }
    e_rls = errs[str(RLS_LAMBDA)]
    mse_rls = (e_rls**2).mean(axis=0)
    kf_osc = oscillation(e_kf)

    kf_w, rls_w = window_means(mse_kf), window_means(mse_rls)
    changes = np.zeros(N_SAMPLES, bool)  # 20 samples after each change of acceleration
    for c in CHANGES:
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
        "rls_oscillates_more_than_kf": bool(
            sweep[str(RLS_LAMBDA)]["oscillation"]["sign_changes"]["pre"]
            > kf_osc["sign_changes"]["pre"]),
        "rls_oscillates_more_after_acceleration_changes": sweep[str(RLS_LAMBDA)][
            "oscillation"]["more_after_changes"],
    }
    figures: dict[str, Any] = {
        "runs": runs,
        "seed": seed,
        "windows": [list(w) for w in WINDOWS],
        "kf_mse_windows": kf_w,
        "rls_mse_windows": rls_w,
        "kf_mse": float(mse_kf[1:].mean()),
        "rls_mse": float(mse_rls[1:].mean()),
        "kf_mse_after_warmup": float(mse_kf[after].mean()),
        "rls_mse_after_warmup": float(mse_rls[after].mean()),
        "rls_over_kf_after_warmup": float(mse_rls[after].mean() / mse_kf[after].mean()),
        "rls_noise_floor": NOISE_VAR / RLS_M,
        "kf_mse_curve": mse_kf.tolist(),
        "rls_mse_curve": mse_rls.tolist(),
        "lambda_sweep": sweep,
        "kf_oscillation": kf_osc,
        "noise_variance": NOISE_VAR,
        "definitions": {
            "error": "one-step prediction error: H x̄_k − p_k (KF), ŵ_{k−1}ᵀ ỹ_k − p_k (RLS)",
            "mse_curve": "ensemble mean over runs of the squared error, per k = 0…359",
            "mse_windows": "mean of the curve over each window [a, b) of k, in order",
            "mse": "mean of the curve over k = 1…359",
            "after_warmup": "k = 60…359",
            "oscillation": "see mvtrack.experiments.predictors.oscillation",
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
            f"MSE over k ∈ [{a}, {b})",
            proto["kf_first_30"] if first else proto["kf_after"],
            kf_v,
            proto["rls_first_30"] if first else "2.0–2.8",
            rls_v,
        ])
    rows.append(["MSE, all k ≥ 1", "—", figures["kf_mse"], "—", figures["rls_mse"]])
    ko, ro = kf_osc, sweep[str(RLS_LAMBDA)]["oscillation"]
    rows.append(["sign changes of the error, 30 samples before → after each change",
                 "KF changes little", f"{ko['sign_changes']['pre']:.3f} → "
                 f"{ko['sign_changes']['post']:.3f}", "RLS oscillates at each change",
                 f"{ro['sign_changes']['pre']:.3f} → {ro['sign_changes']['post']:.3f}"])
    rows.append(["share of error power at ≥ 0.25 cycles/sample, before → after", "—",
                 f"{ko['hf_share']['pre']:.3f} → {ko['hf_share']['post']:.3f}", "—",
                 f"{ro['hf_share']['pre']:.3f} → {ro['hf_share']['post']:.3f}"])
    for lam in LAMBDAS:
        sw = sweep[str(lam)]
        o = sw["oscillation"]
        rows.append([
            f"RLS λ = {lam}: MSE k ≥ 60; sign changes before → after (z); more oscillation "
            "after the changes", "—", "—", "oscillates",
            f"{sw['mse_after_warmup']:.3g}; {o['sign_changes']['pre']:.3f} → "
            f"{o['sign_changes']['post']:.3f} (z = {o['sign_changes']['z']:.1f}); "
            + ("yes" if o["more_after_changes"] else "**no**"),
        ])
    notes = report_notes(figures)
    return Report(
        name="predictors",
        title="X1 — paper 1 Figs. 5–8: KF vs RLS one-step prediction error (m²)",
        figures=figures,
        columns=["quantity", "SPEC prototype / paper, KF", "ours KF",
                 "SPEC prototype / paper, RLS", "ours RLS (λ = 0.98)"],
        rows=rows,
        notes=notes,
        plots=report_plots(p, acc, y, e_kf, errs, mse_kf, sweep),
    )
