"""X1's signal and error curves: the braking trajectory, the KF's and the RLS predictor's errors.

Their oscillation after each change of acceleration (:data:`CHANGES`) and the mean errors over
the windows of the paper's Figs. 5-8 (:data:`WINDOWS`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

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
