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
#: samples at which the acceleration changes (t = 2, 5, 7, 10 s)
CHANGES = (60, 150, 210, 300)
#: samples compared after and before each change by :func:`oscillation`
OSC_WIDTH = 30
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
    return rls_run(y, p, lam, M)[0]


def rls_run(y: FloatArray, p: FloatArray, lam: float = RLS_LAMBDA, M: int = RLS_M
            ) -> tuple[FloatArray, FloatArray]:
    """One-step RLS prediction errors (runs, K) and the weights ŵ_{k−1} that made each
    prediction (runs, K, M)."""
    runs, K = y.shape
    state = rls.init(runs, M, P0)
    err = np.empty((runs, K))
    weights = np.empty((runs, K, M))
    for k in range(K):
        weights[:, k] = state.w
        err[:, k] = rls.predict(state) - p[k]
        state, _ = rls.update(state, y[:, k], lam, c=P0)
    return err, weights


def oscillation(err: FloatArray, width: int = OSC_WIDTH) -> dict[str, Any]:
    """How much the one-step error oscillates after each change of acceleration, and before.

    For each change k_c of :data:`CHANGES`, the ``width`` samples after it, [k_c, k_c + w),
    are compared with the ``width`` samples before it, [k_c − w, k_c), run by run (the same
    noise in both):

    - ``sign_changes``: the share of consecutive errors of opposite sign (0.5 for white
      noise; below for an error that drifts slowly, above for one that alternates);
    - ``hf_share``: the share of the error's power at frequencies ≥ 0.25 cycles per sample
      (periodogram of the window minus its mean);
    - ``mean_error_lobes``: the number of alternating lobes of the ensemble-mean error after
      the change (samples where the mean is more than 3 standard errors from 0; a step
      response that overshoots and rings has ≥ 2).

    An oscillation *at the changes* shows as post − pre differences of the first two that are
    positive and significant over the runs (``z`` = mean difference / its standard error).
    """
    runs = err.shape[0]

    def sign_rate(e: FloatArray) -> FloatArray:
        return (np.sign(e[:, 1:]) != np.sign(e[:, :-1])).mean(axis=1)

    def hf_share(e: FloatArray) -> FloatArray:
        e = e - e.mean(axis=1, keepdims=True)
        power = np.abs(np.fft.rfft(e, axis=1)) ** 2
        f = np.fft.rfftfreq(e.shape[1])
        return power[:, f >= 0.25].sum(axis=1) / np.maximum(power.sum(axis=1), 1e-300)

    mean, se = err.mean(axis=0), err.std(axis=0, ddof=1) / np.sqrt(max(runs - 1, 1))
    out: dict[str, Any] = {"changes": list(CHANGES), "width": width, "per_change": {}}
    diffs: dict[str, list[FloatArray]] = {"sign_changes": [], "hf_share": []}
    per_run: dict[str, dict[str, list[FloatArray]]] = {
        key: {"pre": [], "post": []} for key in diffs}
    for c in CHANGES:
        post, pre = err[:, c : c + width], err[:, c - width : c]
        entry: dict[str, Any] = {}
        for key, fn in (("sign_changes", sign_rate), ("hf_share", hf_share)):
            a, b = fn(post), fn(pre)
            entry[key] = {"post": float(a.mean()), "pre": float(b.mean())}
            diffs[key].append(a - b)
            per_run[key]["post"].append(a)
            per_run[key]["pre"].append(b)
        sig = np.sign(mean[c : c + width]) * (np.abs(mean[c : c + width]) > 3 * se[c : c + width])
        nz = sig[sig != 0]
        entry["mean_error_lobes"] = int(1 + np.count_nonzero(np.diff(nz))) if nz.size else 0
        entry["mean_error_peak"] = float(np.abs(mean[c : c + width]).max())
        out["per_change"][str(c)] = entry
    for key, d in diffs.items():
        d = np.mean(d, axis=0)  # per run: mean over the changes of post − pre
        z = float(d.mean() / (d.std(ddof=1) / np.sqrt(runs))) if runs > 1 and d.std() > 0 else 0.0
        out[key] = {
            "post": float(np.mean([v[key]["post"] for v in out["per_change"].values()])),
            "pre": float(np.mean([v[key]["pre"] for v in out["per_change"].values()])),
            "post_minus_pre": float(d.mean()),
            "z": z,
        }
        for when in ("pre", "post"):  # 95 % interval of the mean over runs
            v = np.mean(per_run[key][when], axis=0)
            half = 1.96 * v.std(ddof=1) / np.sqrt(runs) if runs > 1 else 0.0
            out[key][f"{when}_ci95"] = [float(v.mean() - half), float(v.mean() + half)]
    # "whenever the acceleration changes": more oscillation after the changes than before them
    out["more_after_changes"] = bool(out["sign_changes"]["z"] > 3 and out["hf_share"]["z"] > 3)
    out["rings"] = bool(max(v["mean_error_lobes"] for v in out["per_change"].values()) >= 3)
    return out


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
    notes = _notes(figures)
    return Report(
        name="predictors",
        title="X1 — paper 1 Figs. 5–8: KF vs RLS one-step prediction error (m²)",
        figures=figures,
        columns=["quantity", "SPEC prototype / paper, KF", "ours KF",
                 "SPEC prototype / paper, RLS", "ours RLS (λ = 0.98)"],
        rows=rows,
        notes=notes,
        plots=_plots(p, acc, y, e_kf, errs, mse_kf, sweep),
    )


def _notes(fig: dict[str, Any]) -> str:
    c = fig["checks"]
    yes = {True: "yes", False: "**no**"}
    sw = fig["lambda_sweep"]
    main = sw[str(RLS_LAMBDA)]
    ko = fig["kf_oscillation"]
    w = ", ".join(f"{v:.2f}" for v in main["mean_weights_after_warmup"])
    per_lambda = "; ".join(
        f"λ = {lam}: {sw[str(lam)]['oscillation']['sign_changes']['pre']:.2f} → "
        f"{sw[str(lam)]['oscillation']['sign_changes']['post']:.2f} (z = "
        f"{sw[str(lam)]['oscillation']['sign_changes']['z']:.1f}), power share "
        f"{sw[str(lam)]['oscillation']['hf_share']['pre']:.2f} → "
        f"{sw[str(lam)]['oscillation']['hf_share']['post']:.2f} (z = "
        f"{sw[str(lam)]['oscillation']['hf_share']['z']:.1f})"
        for lam in LAMBDAS
    )
    appears = [str(lam) for lam in LAMBDAS if sw[str(lam)]["oscillation"]["more_after_changes"]]
    lines = [
        f"{fig['runs']} Monte-Carlo runs (seed {fig['seed']}), the same measurement noise "
        "(variance 5 m²) for both predictors; ensemble mean squared one-step prediction "
        "error averaged over each window of k. The paper gives curves only (Figs. 7–8); the "
        "'prototype' columns are the values SPEC X1 reports from a prototype.",
        "",
        "**The oscillation of Fig. 7.** Paper 1 says RLS \"errs and oscillates whenever the "
        "acceleration changes\" (k = 60, 150, 210, 300). We measured, run by run, how often "
        "the error changes sign and what share of its power lies at ≥ 0.25 cycles per sample, "
        "in the 30 samples after each change against the 30 before it (z: the mean "
        "difference over runs in standard errors). RLS's error does oscillate far more than "
        f"the KF's (sign changes {main['oscillation']['sign_changes']['pre']:.2f} against "
        f"{ko['sign_changes']['pre']:.2f} of consecutive samples; white noise would give "
        "0.5), but it does so all the time, not at the changes: "
        f"{per_lambda}. More oscillation after the changes than before them (both z > 3) for "
        f"λ ∈ {{{', '.join(appears) or 'none'}}}. The ensemble-mean error (the deterministic "
        "response to each change) has at most "
        f"{max(v['mean_error_lobes'] for v in main['oscillation']['per_change'].values())} "
        "significant lobe(s) after a change for λ = 0.98: it does not ring. The oscillation is "
        "the measurement noise passed through RLS's three taps, whose weights keep adapting "
        "to it; a smaller λ (shorter memory) makes it stronger.",
        "",
        f"**Why RLS's error is {fig['rls_over_kf_after_warmup']:.1f}× the KF's after warm-up "
        f"({fig['rls_mse_after_warmup']:.2f} against {fig['kf_mse_after_warmup']:.2f} m², "
        "k ≥ 60), where the paper calls the overall tracking ability similar.** With M = 3 and "
        f"noisy positions RLS converges to weights ≈ ({w}) on [y_(k−1), y_(k−2), y_(k−3)] "
        "(mean over runs and k ≥ 60): an average of the last three measurements, not the "
        "polynomial extrapolator (3, −3, 1). Any 3-tap predictor that passes a constant "
        "position (Σw = 1) passes at least R/M = "
        f"{fig['rls_noise_floor']:.2f} m² of the noise (the minimum of R Σw²); ours passes "
        f"R·E‖ŵ‖² = {NOISE_VAR * main['noise_gain_after_warmup']:.2f} m², and the average lags "
        "the moving vehicle. The KF averages over its whole memory with the right motion "
        "model, so it keeps only a small part of the noise. In RMS terms the errors are "
        f"{np.sqrt(fig['kf_mse_after_warmup']):.2f} m (KF) and "
        f"{np.sqrt(fig['rls_mse_after_warmup']):.2f} m (RLS), both well under a car's "
        "length: similar at the scale of tracking, not at the scale of the MSE.",
        "",
        "Paper's other qualitative claims, checked on our curves:",
        "",
        f"- KF has a large initial error (window [1, 30) above twice its mean after k = 60): "
        f"{yes[c['kf_initial_error_large']]}. x̄₀ = 0 equals the true start p₀ = 0; the "
        "initial error comes from the unknown velocity (50 km/h against x̄₀'s 0).",
        f"- KF error rises after the acceleration changes (20 samples after each, against the "
        f"rest after k = 60, by > 10 %): {yes[c['kf_rises_at_acceleration_changes']]}.",
        f"- RLS error rises after the acceleration changes: "
        f"{yes[c['rls_rises_at_acceleration_changes']]}.",
        f"- KF removes most of the noise (median MSE after k = 60 below half the noise "
        f"variance): {yes[c['kf_removes_most_noise']]}.",
        f"- RLS has a large initial error until it converges: "
        f"{yes[c['rls_initial_error_large']]}.",
        f"- RLS varies more than the KF after warm-up: {yes[c['rls_varies_more_than_kf']]}.",
    ]
    return "\n".join(lines)


def _plots(p, acc, y, e_kf, errs, mse_kf, sweep) -> dict[str, Any]:
    from matplotlib.figure import Figure

    from mvtrack.viz.plots import PALETTE, TRUTH_COLOR, grouped_bars

    t = np.arange(N_SAMPLES) * DT
    k = np.arange(N_SAMPLES)
    rls_color = {str(lam): PALETTE[i + 1] for i, lam in enumerate(LAMBDAS)}
    kf_color = PALETTE[0]
    main = str(RLS_LAMBDA)

    def changes(ax, scale: float = 1.0) -> None:
        for i, c in enumerate(CHANGES):
            ax.axvline(c * scale, color="0.6", lw=0.8, ls=":",
                       label="acceleration changes" if i == 0 else None)

    plots: dict[str, Any] = {}
    fig = Figure(figsize=(7, 3.5), layout="constrained")
    ax = fig.subplots()
    ax.plot(t, y[0], ".", ms=2, color="0.55", label="measurements (run 0)")
    ax.plot(t, p, "-", color=TRUTH_COLOR, label="true position")
    changes(ax, DT)
    ax.set(xlabel="time (s)", ylabel="position (m)", title="Fig. 5: trajectory")
    ax.legend(fontsize=8)
    plots["fig5_trajectory"] = fig

    fig = Figure(figsize=(7, 3), layout="constrained")
    ax = fig.subplots()
    ax.step(t, acc, where="post", color=TRUTH_COLOR, label="true acceleration")
    ax.set(xlabel="time (s)", ylabel="acceleration (m/s²)", title="Fig. 6: acceleration")
    ax.legend(fontsize=8)
    plots["fig6_acceleration"] = fig

    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.plot(k, errs[main][0], "-", color=rls_color[main], lw=0.9, label=f"RLS λ = {main}")
    ax.plot(k, e_kf[0], "-", color=kf_color, lw=1.3, label="KF")
    changes(ax)
    ax.axhline(0.0, color="black", lw=0.6)
    ax.set(xlabel="k", ylabel="one-step prediction error (m)", ylim=(-8, 8),
           title="Fig. 7: one run (run 0)")
    ax.legend(fontsize=8, ncol=3, loc="upper right")
    plots["fig7_one_run"] = fig

    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.subplots()
    ax.semilogy(k[1:], (errs[main] ** 2).mean(axis=0)[1:], color=rls_color[main], lw=1,
                label=f"RLS λ = {main}")
    ax.semilogy(k[1:], mse_kf[1:], color=kf_color, lw=1.3, label="KF")
    ax.axhline(NOISE_VAR, color="black", ls="--", lw=0.8, label="noise variance R")
    ax.axhline(NOISE_VAR / RLS_M, color=rls_color[main], ls="--", lw=0.8,
               label="R / M: floor of any 3-tap average")
    changes(ax)
    ax.set(xlabel="k", ylabel="ensemble MSE (m²)", title="Fig. 8: ensemble mean squared error")
    ax.legend(fontsize=7, ncol=2, loc="upper right")
    plots["fig8_ensemble_mse"] = fig

    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.subplots()
    centres = [0.5 * (a + b) for a, b in WINDOWS]
    for lam, sw in sweep.items():
        ax.semilogy(centres, sw["mse_windows"], "o-", color=rls_color[lam], label=f"RLS λ = {lam}")
    ax.semilogy(centres, window_means(mse_kf), "s--", color=kf_color, label="KF")
    ax.set(xlabel="window centre k", ylabel="window MSE (m²)", title="λ sweep: window MSE")
    ax.legend(fontsize=8)
    plots["lambda_sweep"] = fig

    fig = Figure(figsize=(8, 6), layout="constrained")
    top, bottom = fig.subplots(2, 1)
    cats = ["KF", *(f"RLS λ = {lam}" for lam in LAMBDAS)]
    oscs = [oscillation(e_kf), *(sweep[str(lam)]["oscillation"] for lam in LAMBDAS)]
    for ax, key, label in ((top, "sign_changes", "share of sign changes"),
                           (bottom, "hf_share", "power share ≥ 0.25 cycles/sample")):
        before, after = "30 samples before each change", "30 samples after each change"
        grouped_bars(ax, cats, {
            before: [o[key]["pre"] for o in oscs],
            after: [o[key]["post"] for o in oscs],
        }, errors={before: [o[key]["pre_ci95"] for o in oscs],
                   after: [o[key]["post_ci95"] for o in oscs]},
            colors={before: "0.75", after: PALETTE[1]}, fmt="{:.2f}")
        ax.set_ylabel(label)
        ax.legend(fontsize=7, loc="upper left")
    top.axhline(0.5, color="black", ls=":", lw=0.8)
    top.set_title("Does the error oscillate more after the acceleration changes? (mean over "
                  "runs and the four changes, 95 % intervals)", fontsize=10)
    plots["oscillation"] = fig
    return plots
