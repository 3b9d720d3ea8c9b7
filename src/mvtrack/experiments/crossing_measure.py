"""X7's runs: the crossing targets, their noisy measurements, the tracker run on them, outcomes.

Each run scored by :func:`outcomes` (swap, merge, failure, success); sweeps over the distances and
:data:`RHO_SWEEP`, and the rates with their intervals and paired tests.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import ASSIGN_RULES, assign
from mvtrack.association.distances import DISTANCES, TrackView, pair_distance
from mvtrack.experiments.stats import paired, rate_of
from mvtrack.filters import kalman
from mvtrack.filters.models import constant_acceleration
from mvtrack.sim.crossing import x7_crossing
from mvtrack.types import Detections

N_FRAMES = 100
SIGMA = 1.5
Q = 0.01
#: initial acceleration variance (px²/frame⁴) of the two-point initialisation [R]
ACC_VAR0 = 0.1
LAST = 20
JITTER = 0.25
#: box size for the IoU distance (the targets are points)
BOX = 10.0
#: elongations ρ of the coupled region tried besides the default ρ = 2 (ρ = 1 is eq. (9) here)
RHO_SWEEP = (1.0, 1.5, 3.0, 4.0)


IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]


def truth(runs: int, seed: int, jitter: float) -> FloatArray:
    """True positions (runs, frames, 2 targets, 2) from :func:`x7_crossing`."""
    if jitter == 0:
        scene = x7_crossing(0, 0.0)
        one = np.stack([scene.trajectory(k)[1] for k in (1, 2)], axis=1)
        return np.broadcast_to(one, (runs, *one.shape)).copy()
    children = np.random.SeedSequence([seed, 7]).spawn(runs)
    out = np.empty((runs, N_FRAMES, 2, 2))
    for i, child in enumerate(children):  # scene construction, not the per-frame path
        scene = x7_crossing(np.random.default_rng(child), jitter)
        out[i] = np.stack([scene.trajectory(k)[1] for k in (1, 2)], axis=1)
    return out


def measurements(xy: FloatArray, rng: np.random.Generator) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Noisy measurements (runs, frames, 2, 2) and a per-frame flag that swaps their order."""
    z = xy + rng.normal(0.0, SIGMA, xy.shape)
    return z, rng.random(xy.shape[:2]) < 0.5


def simulate(
    z: FloatArray,
    flip: NDArray[np.bool_],
    distance: str,
    rule: str,
    **params: Any,
) -> tuple[IntArray, FloatArray]:
    """Track both targets of every run; return which target each track took and its estimate.

    Parameters
    ----------
    z : (S, T, 2, 2)
        Measurements of target 0 and 1 per run and frame.
    flip : (S, T) bool
        Measurement order per frame (True: target 1's measurement is listed first).
    distance, rule, **params
        Association distance (with parameters) and assignment rule.

    Returns
    -------
    taken : (S, T, 2) intp
        Target whose measurement each track took (−1: none; frames 0–1 are the
        initialisation, track k takes target k).
    est : (S, T, 2, 2)
        Filtered positions.
    """
    s_runs, t_frames = z.shape[:2]
    n = 2 * s_runs
    model = constant_acceleration(1.0, Q, SIGMA**2)
    r = SIGMA**2
    # per-axis filters, index f = (run * 2 + track) * 2 + axis
    z0 = z[:, 0].reshape(-1)
    z1 = z[:, 1].reshape(-1)
    x = np.stack([z1, z1 - z0, np.zeros_like(z1)], axis=1)
    p0 = np.array([[r, r, 0.0], [r, 2 * r, 0.0], [0.0, 0.0, ACC_VAR0]])
    P = np.broadcast_to(p0, (2 * n, 3, 3)).copy()
    # all (track, detection) pairs within each run: ungated
    run = np.repeat(np.arange(s_runs), 4)
    ti = run * 2 + np.tile([0, 0, 1, 1], s_runs)
    dj = run * 2 + np.tile([0, 1, 0, 1], s_runs)
    taken = np.full((s_runs, t_frames, 2), -1, dtype=np.intp)
    taken[:, :2] = [0, 1]
    est = np.full((s_runs, t_frames, 2, 2), np.nan)
    est[:, 1] = z[:, 1]
    wh = np.full((n, 2), BOX)
    for k in range(2, t_frames):
        x, P = kalman.predict(x, P, model.F, model.Q)
        cov = np.zeros((n, 2, 2))
        cov[:, 0, 0] = P[0::2, 0, 0]
        cov[:, 1, 1] = P[1::2, 0, 0]
        view = TrackView(x[:, 0].reshape(n, 2), cov, cov + r * np.eye(2), x[:, 1].reshape(n, 2), wh)
        order = np.where(flip[:, k, None], [1, 0], [0, 1])  # (S, 2): origin of det rows
        origin = order.reshape(-1)
        det_xy = z[np.repeat(np.arange(s_runs), 2), k, origin]
        dets = Detections(k, det_xy, wh)
        cost = pair_distance(distance, view, dets, ti, dj, **params)
        u = 4.0 * float(np.abs(cost).max()) + 1.0  # large enough to match both tracks
        a = assign(ti, dj, cost, n, n, rule, unmatched_cost=u)  # type: ignore[arg-type]
        det = np.full(n, -1, dtype=np.intp)  # each track's detection row, −1: none
        det[a.track] = a.det
        got = det >= 0
        meas = np.where(got[:, None], det_xy[np.maximum(det, 0)], np.nan)
        taken[:, k] = np.where(got, origin[np.maximum(det, 0)], -1).reshape(s_runs, 2)
        x, P = kalman.update(x, P, meas.reshape(-1, 1), model.H, model.R)
        est[:, k] = x[:, 0].reshape(s_runs, 2, 2)
    return taken, est


def _swaps(taken: IntArray) -> NDArray[np.bool_]:
    """Runs where track 1 took target 2's measurement in most of the last frames."""
    return (taken[:, -LAST:, 0] == 1).sum(axis=1) > LAST // 2


def outcomes(taken: IntArray) -> dict[str, NDArray[np.bool_]]:
    """Per run, over the last :data:`LAST` frames (each "in most of them"):

    - ``swap``: track 1 took T2's measurement (the paper's measure of failure);
    - ``merge``: both tracks took the same target's measurement (possible under the
      non-exclusive nearest rule; the literal eq. (10) fails this way);
    - ``failure``: either track is not on its own target (``swap`` or ``merge`` or worse);
    - ``success``: both tracks on their own targets (``~failure``).
    """
    last = taken[:, -LAST:]
    own = (last == [0, 1]).sum(axis=1) > LAST // 2  # (S, 2)
    failure = ~own.all(axis=1)
    return {
        "swap": _swaps(taken),
        "merge": (last[..., 0] == last[..., 1]).sum(axis=1) > LAST // 2,
        "failure": failure,
        "success": ~failure,
    }


def sweep_runs(
    xy: FloatArray, rng: np.random.Generator, label: str
) -> tuple[dict[tuple[str, str], dict[str, NDArray[np.bool_]]], dict[str, Any], Any]:
    """Every distance × rule (and the ρ sweep) on one draw of the noise."""
    z, flip = measurements(xy, rng)
    results: dict[tuple[str, str], dict[str, NDArray[np.bool_]]] = {}
    examples: dict[tuple[str, str], FloatArray] = {}
    combos: list[tuple[str, str, dict[str, float]]] = [
        (d, rule, {}) for d in DISTANCES for rule in ASSIGN_RULES
    ]
    combos += [("coupled", rule, {"rho": r}) for r in RHO_SWEEP for rule in ASSIGN_RULES]
    rho_rate: dict[str, dict[str, float]] = {}
    from tqdm import tqdm

    bar = tqdm(combos, desc=f"crossing {label}", disable=not sys.stderr.isatty())
    for dist, rule, params in bar:
        taken, est = simulate(z, flip, dist, rule, **params)
        if params:  # the ρ sweep of the coupled region
            rho_rate.setdefault(f"{params['rho']:g}", {})[rule] = float(_swaps(taken).mean())
            continue
        results[dist, rule] = outcomes(taken)
        examples[dist, rule] = est[0]
    return results, rho_rate, (z[0], examples)


def rate_table(results: dict[tuple[str, str], dict[str, NDArray[np.bool_]]], key: str
           ) -> dict[str, dict[str, float]]:
    out: dict[str, dict[str, float]] = {}
    for (dist, rule), o in results.items():
        out.setdefault(dist, {})[rule] = float(o[key].mean())
    return out


def cis(results: dict[tuple[str, str], dict[str, NDArray[np.bool_]]], key: str
         ) -> dict[str, dict[str, list[float]]]:
    out: dict[str, dict[str, list[float]]] = {}
    for (dist, rule), o in results.items():
        out.setdefault(dist, {})[rule] = rate_of(o[key])["ci95"]
    return out


def paired_rates(results: dict[tuple[str, str], dict[str, NDArray[np.bool_]]]
            ) -> dict[str, dict[str, Any]]:
    """coupled vs uncoupled on the same noise: discordant runs and an exact McNemar test."""
    out = {}
    for rule in ASSIGN_RULES:
        t = paired(results["coupled", rule]["swap"], results["uncoupled", rule]["swap"])
        out[rule] = {"only_coupled_swaps": t["only_a"], "only_uncoupled_swaps": t["only_b"],
                     "mcnemar_exact_p": t["p"]}
    return out
