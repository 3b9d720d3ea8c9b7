"""X4: paper 1's synthetic video of 9 vehicles, KF vs RLS end to end (Figs. 9-10, SPEC §5 X4).

The scene (:func:`mvtrack.sim.scenes.x4_nine_vehicles`: 320×240, 30 fps, 240 frames, flat grey,
no noise) is rendered and run through the whole pipeline: disturbance map (SPEC §1.1 [R]),
paper 1's tracker (:func:`mvtrack.tracking.paper1` with the synthetic experiment's 10 px
circular gate, non-exclusive nearest, 3-frame coasting, warm-up gate centre ``2y_k − y_{k−1}``)
with the per-axis CA Kalman filter (R = 1 px², q = 0.1) or the RLS predictor (M = 3,
λ = 0.98), and template matching for stopped vehicles. Counted as in SPEC X4: tracks with
at least 5 associations; tracks per vehicle by majority pairing with the ground truth; where
the fast vehicle V9's track breaks.

Two background protocols are reported. *Primed* (the headline, JSON ``tracks``): the
disturbance map has seen 50 frames of the empty road before frame 0, as a camera that has
been running; *cold start* (``tracks_cold_start``): ``B_0 = I_0`` exactly as SPEC §1.1 [R],
where V1-V8 are already in view at frame 0 and leave a ghost blob behind them for the first
frames; under non-exclusive association the ghost tracks then ride on the vehicles' blobs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments._video import (
    breaks,
    default_config,
    summarise,
    track_scene,
    trajectory_plot,
)
from mvtrack.experiments.report import Report
from mvtrack.sim.scenes import x4_nine_vehicles
from mvtrack.tracking import paper1

PREDICTORS = ("kalman-ca", "rls")
PAPER = {
    "tracks": {"kalman-ca": 10, "rls": 11},
    "vehicles": 9,
    "v9_breaks": {"kalman-ca": "once, mid-way (bend B)", "rls": "twice: mid-way and at bend A"},
}
#: frames of V9's two bends (SPEC X4: arc A ≈ 58–64, arc B ≈ 66–68), with slack
BENDS = {"A": (55, 64), "B": (65, 72)}
PRIME_FRAMES = 50
#: the blob stage of SPEC §1.1 [R] (3×3 opening, area ≥ 20 px, no closing): X4's vehicles are
#: one-tone rectangles on a flat, noiseless road, and a closing would merge V6 and V7, which
#: pass 9.6 px apart
SPEC_BLOBS = {"close_size": 0, "min_area": 20.0}
MIN_ASSOC = 5


def _where(frame: int) -> str:
    for name, (lo, hi) in BENDS.items():
        if lo <= frame <= hi:
            return f"bend {name}"
    return "straight"


def _v9_breaks(run: Any, v9: int) -> list[dict[str, Any]]:
    frames, tracks = run.match.sequence(v9)
    f_all, xy_all = run.scene.trajectory(v9)
    out = []
    for f, old, new in breaks(frames, tracks):
        xy = xy_all[np.searchsorted(f_all, f)]
        out.append({"frame": f, "from_track": old, "to_track": new,
                    "xy": [round(float(xy[0]), 1), round(float(xy[1]), 1)], "where": _where(f)})
    return out


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Track X4 with KF and RLS (paper 1 preset, 10 px gate) and with the modern default.

    ``runs`` renderings with seeds ``seed, seed+1, ...`` (default 1: the X4 video has no noise,
    so every rendering is the same picture; the counts are reported per run).
    """
    n_runs = 1 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be at least 1, got {n_runs}")
    scene = x4_nine_vehicles()
    v9 = int(scene.ids_of("fast")[0])
    configs = {p: paper1(p, fps=scene.fps, gate_px=10.0) for p in PREDICTORS}
    configs["default"] = default_config(scene)
    per_run: list[dict[str, Any]] = []
    last: dict[str, Any] = {}
    for r in range(n_runs):
        s = seed + r
        entry: dict[str, Any] = {"seed": s}
        for name, cfg in configs.items():
            primed = track_scene(scene, cfg, seed=s, prime=PRIME_FRAMES,
                                 detector_params=SPEC_BLOBS)
            cold = track_scene(scene, cfg, seed=s, prime=0, detector_params=SPEC_BLOBS)
            entry[name] = {
                "primed": summarise(primed, MIN_ASSOC) | {"v9_breaks": _v9_breaks(primed, v9)},
                "cold_start": summarise(cold, MIN_ASSOC) | {"v9_breaks": _v9_breaks(cold, v9)},
            }
            last[name] = (primed, cold)
        per_run.append(entry)

    def med(name: str, protocol: str, key: str = "tracks") -> float:
        return float(np.median([e[name][protocol][key] for e in per_run]))

    first = per_run[0]
    tracks = {p: int(med(p, "primed")) for p in PREDICTORS}
    figures: dict[str, Any] = {
        "paper": PAPER,
        "tracks": tracks,
        "tracks_cold_start": {p: int(med(p, "cold_start")) for p in PREDICTORS},
        "default_tracks": {"primed": int(med("default", "primed")),
                           "cold_start": int(med("default", "cold_start"))},
        "tracks_per_vehicle": {
            p: first[p]["primed"]["tracks_per_object"] for p in (*PREDICTORS, "default")
        },
        "v9_breaks": {p: first[p]["primed"]["v9_breaks"] for p in (*PREDICTORS, "default")},
        "v9_breaks_cold_start": {p: first[p]["cold_start"]["v9_breaks"] for p in PREDICTORS},
        "spurious": {p: first[p]["primed"]["spurious"] for p in (*PREDICTORS, "default")},
        "min_associations": MIN_ASSOC,
        "prime_frames": PRIME_FRAMES,
        "runs": per_run,
    }

    def v9_text(name: str, protocol: str = "primed") -> str:
        b = first[name][protocol]["v9_breaks"]
        return "none" if not b else "; ".join(f"f{x['frame']} ({x['where']})" for x in b)

    def one_track(name: str) -> str:
        tpv = first[name]["primed"]["tracks_per_object"]
        return f"{sum(1 for v in range(1, 9) if tpv[v] == 1)}/8"

    rows = [
        ["tracks (≥ 5 associations), primed background", "KF 10, RLS 11",
         tracks["kalman-ca"], tracks["rls"], int(med("default", "primed"))],
        ["tracks, cold start (B_0 = I_0)", "—",
         int(med("kalman-ca", "cold_start")), int(med("rls", "cold_start")),
         int(med("default", "cold_start"))],
        ["V1–V8 with exactly one track", "8/8 (both)",
         one_track("kalman-ca"), one_track("rls"), one_track("default")],
        ["tracks on V9 (fast, curving)", "KF 2, RLS 3",
         first["kalman-ca"]["primed"]["tracks_per_object"][v9],
         first["rls"]["primed"]["tracks_per_object"][v9],
         first["default"]["primed"]["tracks_per_object"][v9]],
        ["V9 track breaks", "KF mid-way; RLS mid-way and at A",
         v9_text("kalman-ca"), v9_text("rls"), v9_text("default")],
        ["spurious tracks", "—", first["kalman-ca"]["primed"]["spurious"],
         first["rls"]["primed"]["spurious"], first["default"]["primed"]["spurious"]],
    ]
    def said(name: str, paper_tracks: int) -> str:
        verdict = "as the paper" if tracks[name] == paper_tracks else "paper"
        return (f"{name} {tracks[name]} tracks ({verdict} {paper_tracks}), "
                f"V9 breaks: {v9_text(name)}")

    compare = "; ".join([said("kalman-ca", 10), said("rls", 11)])
    notes = f"""
Setup: SPEC §5 X4 scene rendered by `mvtrack.sim.render`, disturbance map exactly as SPEC
§1.1 [R] (T = 25, β_min = 0.02, 3×3 opening, area ≥ 20 px, no closing), paper 1 tracker
with a 10 px circular gate (`paper1(predictor, gate_px=10)`), template matching on.
"default" is the `default` preset as `mvtrack track` uses it (`mvtrack.tracking.default`
with the pipeline's size-dependent defaults).
Tracks are counted when they have ≥ {MIN_ASSOC} associations and are assigned to the vehicle
they are paired with in most of their frames (pairs: Hungarian per frame on centre
distance ≤ max(6 px, 0.75 × box size)). Primed: the detector saw {PRIME_FRAMES} frames of
the empty road first. Cold start: B_0 = I_0 with V1–V8 in view, which leaves a ghost blob
behind each of them; with non-exclusive nearest association the ghost tracks then share the
vehicles' blobs and survive, so every such vehicle is followed by duplicate tracks.

Compared with the paper (primed background): {compare}.
Runs: {n_runs} (the scene has no noise; every rendering is identical).
"""
    plots = {
        p: trajectory_plot(last[p][0], f"X4, {p} (paper 1 preset, 10 px gate)")
        for p in (*PREDICTORS, "default")
    }
    return Report(
        name="synthetic-traffic",
        title="X4 — paper 1 synthetic video, 9 vehicles: KF vs RLS end to end (Figs. 9–10)",
        figures=figures,
        columns=["quantity", "paper", "KF (kalman-ca)", "RLS", "modern default"],
        rows=rows,
        notes=notes,
        plots=plots,
    )
