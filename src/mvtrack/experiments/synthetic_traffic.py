"""X4: paper 1's synthetic video of 9 vehicles, KF vs RLS end to end (Figs. 9-10, SPEC §5 X4).

The scene (:func:`mvtrack.sim.nine_vehicles.x4_nine_vehicles`: 320×240, 30 fps, 240 frames,
flat grey, no noise) is rendered and run through the whole pipeline: disturbance map exactly as
SPEC §1.1 [R] (T = 25, β_k = max(1/(k+1), 0.02), B₀ = I₀, 3×3 opening, area ≥ 20 px, no closing),
paper 1's tracker (:func:`mvtrack.tracking.paper1` with the synthetic experiment's 10 px
circular gate, non-exclusive nearest, 3-frame coasting, warm-up gate centre ``2y_k − y_{k−1}``)
with the per-axis CA Kalman filter or the RLS predictor (M = 3, λ = 0.98), both with
R = 1 px² and the KF's q = 0.1 (SPEC X4 [R]), and template matching for stopped vehicles.
Counted as in SPEC X4: tracks with at least 5 associations; tracks per vehicle by majority
pairing with the ground truth; where the fast vehicle V9's track breaks, and why: its gate
centre's distance from V9 (the prediction error) frame by frame against the 10 px gate, and
whether the track was still in the warm-up.

Variants (each with its reason in the report): a primed background (the detector first sees
50 frames of the empty road), the paper presets' noise values (R = 4 px², q = 0.05), the
modern default, and a sweep of the KF's q.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments._video import (
    PAPER_TEMPLATES,
    SceneRun,
    breaks,
    default_config,
    default_frame_size,
    prediction_errors,
    summarise,
    track_scene,
    trajectory_plot,
)
from mvtrack.experiments.report import Report
from mvtrack.sim.nine_vehicles import x4_nine_vehicles
from mvtrack.tracking import TrackerConfig, paper1

PREDICTORS = ("kalman-ca", "rls")
PAPER = {
    "tracks": {"kalman-ca": 10, "rls": 11},
    "vehicles": 9,
    "v9_breaks": {"kalman-ca": "once, mid-way (bend B)", "rls": "twice: mid-way and at bend A"},
}
#: frames of V9's two bends (SPEC X4: arc A ≈ 58–64, arc B ≈ 66–68), with slack
BENDS = {"A": (55, 64), "B": (65, 72)}
GATE_PX = 10.0
#: SPEC X4 [R]: R = 1 px² for both predictors, q = 0.1 for the KF
SPEC_R, SPEC_Q = 1.0, 0.1
PRIME_FRAMES = 50
#: the blob stage of SPEC §1.1 [R] (3×3 opening, area ≥ 20 px, no closing)
SPEC_BLOBS = {"close_size": 0, "min_area": 20.0}
MIN_ASSOC = 5
#: tracks born in these first frames and paired with no vehicle are start-up tracks: they ride
#: the ghosts that B₀ = I₀ leaves where the vehicles stood at frame 0
STARTUP_FRAMES = 5
#: KF process noises of the sensitivity sweep
Q_SWEEP = (0.01, 0.03, 0.05, 0.1, 0.3, 1.0)


def spec_config(predictor: str, fps: float, r: float = SPEC_R, q: float = SPEC_Q
                ) -> TrackerConfig:
    """Paper 1's tracker with the 10 px gate and the X4 noise values (R, q)."""
    cfg = paper1(predictor, fps=fps, gate_px=GATE_PX)
    params = {"q": q, "r": r} if predictor == "kalman-ca" else {"r": r}
    return cfg.replace(predictor_params=params)


def _where(frame: int) -> str:
    for name, (lo, hi) in BENDS.items():
        if lo <= frame <= hi:
            return f"bend {name}"
    return "straight"


def v9_breaks(run: SceneRun, v9: int) -> list[dict[str, Any]]:
    """Where V9's track changes, with the old track's prediction error there."""
    frames, tracks = run.match.sequence(v9)
    f_all, xy_all = run.scene.trajectory(v9)
    err = prediction_errors(run, v9)
    out = []
    for f, old, new in breaks(frames, tracks):
        xy = xy_all[np.searchsorted(f_all, f)]
        i = err["frame"].index(f) if f in err["frame"] else None
        out.append({"frame": f, "from_track": old, "to_track": new,
                    "xy": [round(float(xy[0]), 1), round(float(xy[1]), 1)], "where": _where(f),
                    "prediction_error": None if i is None else round(err["error"][i], 2),
                    "in_warmup": None if i is None else err["warmup"][i]})
    return out


def v9_profile(run: SceneRun, v9: int) -> dict[str, Any]:
    """V9's prediction error profile: per frame, and its maximum in each bend."""
    err = prediction_errors(run, v9)
    f = np.asarray(err["frame"])
    e = np.asarray(err["error"], float)
    out: dict[str, Any] = {"frames": f.tolist(), "error": [round(float(v), 3) for v in e],
                           "warmup": err["warmup"]}
    for name, (lo, hi) in BENDS.items():
        sel = (f >= lo) & (f <= hi) & np.isfinite(e)
        out[f"max_error_bend_{name}"] = float(e[sel].max()) if sel.any() else None
        out[f"warmup_at_bend_{name}"] = bool(np.any(np.asarray(err["warmup"])[sel]))
    straight = np.isfinite(e) & ~np.any([(f >= lo) & (f <= hi) for lo, hi in BENDS.values()],
                                        axis=0)
    out["max_error_straight"] = float(e[straight].max()) if straight.any() else None
    return out


def _startup(run: SceneRun) -> tuple[int, int]:
    """Tracks with ≥ MIN_ASSOC associations born in the first frames and paired with nothing,
    and the last frame any of them is output."""
    ids, obj, _ = run.match.majority(MIN_ASSOC)
    cols = run.log.columns()
    n, last = 0, -1
    for t in ids[obj == 0].tolist():  # a handful of tracks, offline
        fr = cols["frame"][cols["track_id"] == t]
        if fr.min() < STARTUP_FRAMES:
            n, last = n + 1, max(last, int(fr.max()))
    return n, last


def _measure(run: SceneRun, v9: int) -> dict[str, Any]:
    s = summarise(run, MIN_ASSOC)
    s["startup_tracks"], s["startup_last_frame"] = _startup(run)
    s["vehicle_tracks"] = s["tracks"] - s["spurious"]
    s["v9_breaks"] = v9_breaks(run, v9)
    s["v9_profile"] = v9_profile(run, v9)
    return s


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Track X4 with KF and RLS (SPEC X4 settings) and the variants.

    ``runs`` renderings with seeds ``seed, seed+1, ...`` (default 1: the X4 video has no noise,
    so every rendering is the same picture; the counts are reported per run).
    """
    n_runs = 1 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be at least 1, got {n_runs}")
    scene = x4_nine_vehicles()
    v9 = int(scene.ids_of("fast")[0])
    fps = scene.fps
    settings: dict[str, tuple[TrackerConfig, int]] = {}
    for p in PREDICTORS:
        settings[p] = (spec_config(p, fps), 0)
        settings[f"{p}, primed"] = (spec_config(p, fps), PRIME_FRAMES)
        settings[f"{p}, R = 4, q = 0.05"] = (paper1(p, fps=fps, gate_px=GATE_PX), 0)
    settings["default"] = (default_config(scene), 0)
    for q in Q_SWEEP:
        settings[f"kalman-ca, q = {q:g}"] = (spec_config("kalman-ca", fps, q=q), 0)
    per_run: list[dict[str, Any]] = []
    first: dict[str, SceneRun] = {}
    for r in range(n_runs):
        s = seed + r
        entry: dict[str, Any] = {"seed": s}
        for name, (cfg, prime) in settings.items():
            size = default_frame_size(scene) if name == "default" else None  # as mvtrack track
            tr = track_scene(scene, cfg, seed=s, prime=prime, detector_params=SPEC_BLOBS,
                             frame_size=size,
                             template_params=None if name == "default" else PAPER_TEMPLATES)
            entry[name] = _measure(tr, v9)
            if r == 0:
                first[name] = tr
        per_run.append(entry)
    res = per_run[0]

    def med(name: str, key: str = "tracks") -> int:
        return int(np.median([e[name][key] for e in per_run]))

    variants = {
        "primed": f"the detector first sees {PRIME_FRAMES} frames of the empty road, as a camera "
        "that ran before the sequence; with B₀ = I₀ the vehicles in view at frame 0 leave "
        "ghost blobs, and paper 1's counts (10, 11) leave no room for such start-up tracks",
        "R = 4, q = 0.05": "the paper presets' values for real video (SPEC §2.1 [R]), the "
        "previous headline: a KF with q/R eight times smaller",
        "default": "the modern default as `mvtrack track` uses it",
        "q sweep": "the KF's process noise q ∈ {" + ", ".join(f"{q:g}" for q in Q_SWEEP)
        + "}: where V9's track breaks",
    }
    figures: dict[str, Any] = {
        "paper": PAPER,
        "setting": {"gate_px": GATE_PX, "r": SPEC_R, "kf_q": SPEC_Q, "rls_lambda": 0.98,
                    "rls_M": 3, "background": "B0 = I0", "blobs": SPEC_BLOBS},
        "tracks": {p: med(p) for p in PREDICTORS},
        "startup_tracks": {p: med(p, "startup_tracks") for p in PREDICTORS},
        "vehicle_tracks": {p: med(p, "vehicle_tracks") for p in PREDICTORS},
        "tracks_per_vehicle": {p: res[p]["tracks_per_object"] for p in PREDICTORS},
        "v9_breaks": {p: res[p]["v9_breaks"] for p in PREDICTORS},
        "v9_prediction": {p: {k: v for k, v in res[p]["v9_profile"].items()
                              if k.startswith(("max_", "warmup_at"))} for p in PREDICTORS},
        "spurious": {p: res[p]["spurious"] for p in PREDICTORS},
        "variants": {name: {"tracks": med(name), "vehicle_tracks": med(name, "vehicle_tracks"),
                            "startup_tracks": med(name, "startup_tracks"),
                            "tracks_per_vehicle": res[name]["tracks_per_object"],
                            "v9_breaks": res[name]["v9_breaks"],
                            "v9_prediction": {k: v for k, v in res[name]["v9_profile"].items()
                                              if k.startswith(("max_", "warmup_at"))}}
                     for name in settings if name not in PREDICTORS},
        "min_associations": MIN_ASSOC,
        "prime_frames": PRIME_FRAMES,
        "runs": per_run,
    }

    def v9_text(name: str) -> str:
        def error(e: float | None) -> str:  # no row of the old track there: it had ended
            return "the old track had ended" if e is None or np.isnan(e) else f"prediction {e} px"

        b = res[name]["v9_breaks"]
        return "none" if not b else "; ".join(
            f"f{x['frame']} ({x['where']}, {error(x['prediction_error'])})" for x in b)

    def one_track(name: str) -> str:
        tpv = res[name]["tracks_per_object"]
        return f"{sum(1 for v in range(1, 9) if tpv[v] == 1)}/8"

    def bend(name: str, b: str) -> str:
        v = res[name]["v9_profile"][f"max_error_bend_{b}"]
        return "—" if v is None else f"{v:.1f}"

    kf, rl = "kalman-ca", "rls"
    rows: list[list[Any]] = [
        ["tracks (≥ 5 associations)", "KF 10, RLS 11", med(kf), med(rl)],
        [f"… of which start-up tracks (born before frame {STARTUP_FRAMES} on B₀ = I₀ ghosts)",
         "—", med(kf, "startup_tracks"), med(rl, "startup_tracks")],
        ["… tracks on vehicles", "KF 10, RLS 11", med(kf, "vehicle_tracks"),
         med(rl, "vehicle_tracks")],
        ["V1–V8 with exactly one track", "8/8 (both)", one_track(kf), one_track(rl)],
        ["tracks on V9 (fast, curving)", "KF 2, RLS 3", res[kf]["tracks_per_object"][v9],
         res[rl]["tracks_per_object"][v9]],
        ["V9 track breaks", "KF mid-way; RLS mid-way and at A", v9_text(kf), v9_text(rl)],
        [f"V9's largest prediction error at bend A / B (px; gate {GATE_PX:g})", "—",
         f"{bend(kf, 'A')} / {bend(kf, 'B')}", f"{bend(rl, 'A')} / {bend(rl, 'B')}"],
    ]
    for tag in ("primed", "R = 4, q = 0.05"):
        a, b = f"{kf}, {tag}", f"{rl}, {tag}"
        rows.append([f"variant *{tag}*: tracks; vehicle tracks; V9 breaks", "—",
                     f"{med(a)}; {med(a, 'vehicle_tracks')}; {v9_text(a)}",
                     f"{med(b)}; {med(b, 'vehicle_tracks')}; {v9_text(b)}"])
    rows.append(["variant *default*: tracks; vehicle tracks; V9 breaks", "—",
                 f"{med('default')}; {med('default', 'vehicle_tracks')}; {v9_text('default')}",
                 "(one tracker)"])
    for q in Q_SWEEP:
        name = f"kalman-ca, q = {q:g}"
        rows.append([f"variant *q sweep*, KF q = {q:g}: V9 bend A / B error (px); breaks", "—",
                     f"{bend(name, 'A')} / {bend(name, 'B')}; {v9_text(name)}", "—"])
    plots = {
        "kalman-ca": trajectory_plot(first[kf], "X4, KF (SPEC X4 settings)",
                                     group_of=lambda v: f"V{v}", spurious="start-up / spurious",
                                     legend_title="track follows"),
        "rls": trajectory_plot(first[rl], "X4, RLS (SPEC X4 settings)",
                               group_of=lambda v: f"V{v}", spurious="start-up / spurious",
                               legend_title="track follows"),
        "v9_prediction": _v9_plot(res, [kf, rl, f"{kf}, R = 4, q = 0.05"]),
    }
    return Report(
        name="synthetic-traffic",
        title="X4 — paper 1 synthetic video, 9 vehicles: KF vs RLS end to end (Figs. 9–10)",
        figures=figures,
        columns=["quantity", "paper", "KF (kalman-ca)", "RLS"],
        rows=rows,
        notes=_notes(figures, res, v9),
        plots=plots,
        variants=variants,
    )


def _notes(fig: dict[str, Any], res: dict[str, Any], v9: int) -> str:
    kf, rl = res["kalman-ca"]["v9_profile"], res["rls"]["v9_profile"]
    old = res["kalman-ca, R = 4, q = 0.05"]
    sweep_breaks = [q for q in Q_SWEEP if res[f"kalman-ca, q = {q:g}"]["v9_breaks"]]
    primed = fig["variants"]
    warm = [f for f, w in zip(kf["frames"], kf["warmup"], strict=True) if w]
    warm_text = f"frames {warm[0]}–{warm[-1]}" if warm else "no frame"
    last = max(res[p]["startup_last_frame"] for p in PREDICTORS)
    single = {p: all(res[p]["tracks_per_object"][v] == 1 for v in range(1, 10))
              for p in PREDICTORS}
    per_vehicle = {p: "one per vehicle" if single[p] else "a vehicle with two" for p in single}
    return f"""
Setup: SPEC §5 X4 scene rendered by `mvtrack.sim.render`, disturbance map exactly as SPEC
§1.1 [R] (B₀ = I₀, T = 25, β_min = 0.02, 3×3 opening, area ≥ 20 px, no closing), paper 1's
tracker with a {GATE_PX:g} px circular gate, R = {SPEC_R:g} px² for both predictors and
q = {SPEC_Q:g} for the KF (SPEC X4 [R]), template matching on. Tracks are counted when they
have ≥ {MIN_ASSOC} associations and are given to the vehicle they are paired with in most of
their frames (pairs: Hungarian per frame on centre distance ≤ max(6 px, 0.75 × box size)).

**Start-up tracks.** With B₀ = I₀, V1–V8 are part of the first background: until the running
mean forgets them, the disturbance map shows each as a ghost where it stood and a leading edge
where it now is, both as separate blobs. {fig['startup_tracks']['kalman-ca']} (KF) and
{fig['startup_tracks']['rls']} (RLS) tracks start on these in the first {STARTUP_FRAMES} frames
and the last of them ends at frame {last}; the vehicles' own tracks start only once the
ghosts fade. Without them the counts are {fig['vehicle_tracks']['kalman-ca']} (KF,
{per_vehicle['kalman-ca']}) and {fig['vehicle_tracks']['rls']} (RLS, {per_vehicle['rls']}:
a start-up track that the pairing gives to it) tracks on vehicles. The primed variant (the
detector sees the empty road first) has no start-up tracks:
{primed['kalman-ca, primed']['tracks']} and {primed['rls, primed']['tracks']} tracks.

**V9, KF against RLS.** Neither predictor loses V9 with the X4 settings, so we do not reproduce
paper 1's KF 10 / RLS 11, and we find the reverse of its "the KF is better under large
accelerations". The data say why. V9 is in the warm-up (gate centre 2y_k − y_(k−1)) only for
its first 6 associations, {warm_text}, long before the bends. At bend A (r = 24 px,
1.5 px/frame²) the gate centre is at most {kf['max_error_bend_A']:.1f} px (KF) and
{rl['max_error_bend_A']:.1f} px (RLS) from V9; at bend B (r = 8 px, 4.5 px/frame²) at most
{kf['max_error_bend_B']:.1f} px (KF) and {rl['max_error_bend_B']:.1f} px (RLS), against the
{GATE_PX:g} px gate. The KF is a smoother: its estimate lags a manoeuvre by an amount set by q/R,
and bend B brings it within {GATE_PX - kf['max_error_bend_B']:.1f} px of the gate. RLS predicts
from its last three measurements only and, on this noise-free video (centroids exact to half a
pixel), that short memory is an advantage at the bends: it has nothing to smooth. With the
paper presets' R = 4 px², q = 0.05 (q/R eight times smaller) the KF's error at bend B is
{old['v9_profile']['max_error_bend_B']:.1f} px and its track breaks there
({len(old['v9_breaks'])} break(s), as paper 1 reports for its KF); in the q sweep (R = 1) it
breaks for q ∈ {{{", ".join(f"{q:g}" for q in sweep_breaks) or "none"}}}. Paper 1's RLS breaks
twice, which needs a prediction error above 10 px at bend A; ours stays at or below
{max(rl['max_error_bend_A'], rl['max_error_bend_B']):.1f} px at both bends. Paper 1 gives
neither the noise of its video nor any RLS setting but M = 3, so we cannot say which of
them made the difference.
"""


def _v9_plot(res: dict[str, Any], names: list[str]) -> Any:
    from matplotlib.figure import Figure

    from mvtrack.viz.colors import PALETTE

    fig = Figure(figsize=(8, 3.8), layout="constrained")
    ax = fig.subplots()
    for name, (lo, hi) in BENDS.items():
        ax.axvspan(lo, hi, color="0.9" if name == "A" else "0.8", label=f"bend {name}")
    prof = res[names[0]]["v9_profile"]
    warm = [f for f, w in zip(prof["frames"], prof["warmup"], strict=True) if w]
    if warm:
        ax.axvspan(warm[0] - 0.5, warm[-1] + 0.5, facecolor="none", hatch="///",
                   edgecolor="0.6", lw=0, label="warm-up: gate centre 2y_k − y_(k−1)")
    labels = {"kalman-ca": "KF, R = 1, q = 0.1 (SPEC X4)", "rls": "RLS, R = 1 (SPEC X4)",
              "kalman-ca, R = 4, q = 0.05": "KF, R = 4, q = 0.05 (variant)"}
    for k, name in enumerate(names):
        prof = res[name]["v9_profile"]
        f = np.asarray(prof["frames"])
        e = np.asarray(prof["error"], float)
        ax.plot(f, e, ".-", color=PALETTE[k], lw=1.2, ms=3, label=labels.get(name, name))
        for b in res[name]["v9_breaks"]:
            ax.plot(b["frame"], min(b["prediction_error"] or 0.0, 25.0), "x", color=PALETTE[k],
                    ms=10, mew=2)
    ax.plot([], [], "x", color="black", ms=8, mew=2, label="track breaks")
    ax.axhline(GATE_PX, color="black", ls="--", lw=1.0, label=f"gate {GATE_PX:g} px")
    ax.set(xlabel="frame", ylabel="gate centre − V9 (px)", xlim=(40, 90), ylim=(0, 25),
           title="V9: distance of the track's gate centre from the vehicle")
    ax.legend(fontsize=7, loc="upper right")
    return fig
