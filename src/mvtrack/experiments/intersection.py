"""X5: paper 1's intersection, reconstructed (Figs. 11-13, SPEC §5 X5).

The synthetic intersection (:func:`mvtrack.sim.scenes.x5_intersection`: 320×240, 30 fps,
360 frames; 11 straight, 6 left-turning, 1 right-turning and 2 waiting vehicles; two-tone
bodies, pixel noise σ = 3, ±1 px camera jitter, bright roadside poles) is rendered and run
through the whole pipeline: disturbance map, tracker, template matching for stopped vehicles.
Trackers: paper 1's system (:func:`mvtrack.tracking.paper1`, 20 px circular gate, nearest,
warm-up) with the CA Kalman filter and with RLS, and the modern default.

Measured per run (seed): per category, the vehicles that got one track covering ≥ 80 % of
their visible frames; whether each waiting vehicle keeps one ID through its wait (frames
60-300), with and without template matching; spurious tracks (≥ 5 associations, paired with
no vehicle in most of their frames) and their likely cause; MOTA and IDF1
(:func:`mvtrack.eval.metrics.evaluate`, IoU ≥ 0.5 — strict for 16×9 px vehicles whose blobs
carry a disturbance-map trail) and the centre-distance pairing used for the counts above.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.config import RunSettings
from mvtrack.experiments._video import (
    SceneRun,
    default_config,
    summarise,
    track_scene,
    trajectory_plot,
)
from mvtrack.experiments.report import Report
from mvtrack.pipeline import resolve_settings
from mvtrack.sim.scenes import x5_intersection
from mvtrack.tracking import paper1

CATEGORIES = ("straight", "left", "right", "waiting")
PAPER = {
    "vehicles": {"straight": 11, "left": 6, "right": 1, "waiting": 2},
    "tracked": "all straight and turning vehicles, by both predictors",
    "extra_tracks": "more trajectories than vehicles (camera motion, colour-split segmentation)",
    "real_time": "30 fps on a 200 MHz Pentium Pro",
}
#: the blob stage exactly as SPEC §1.1 [R] (3×3 opening, area ≥ 20 px, no closing)
SPEC_BLOBS = {"close_size": 0, "min_area": 20.0}
WAIT = (60, 300)
#: a looser NCC threshold than SPEC §1.1 [R]'s 0.8, reported as a variant: under the scene's
#: noise and sub-pixel jitter a standing vehicle's NCC hovers around 0.75-0.82
LOOSE_NCC = 0.7  # frames the waiting vehicles stand at the stop line (SPEC X5)
MIN_ASSOC = 5
COVER = 0.8


def _configs(scene: Any) -> dict[str, Any]:
    fps = scene.fps
    return {
        "kalman-ca": paper1("kalman-ca", fps=fps, gate_px=20.0),
        "rls": paper1("rls", fps=fps, gate_px=20.0),
        "default": default_config(scene),
    }


def _waiting(run: SceneRun) -> list[dict[str, Any]]:
    """Per waiting vehicle: distinct tracks during the wait and whether one ID held it."""
    out = []
    for v in run.scene.ids_of("waiting").tolist():
        frames, tracks = run.match.sequence(v)
        during = (frames >= WAIT[0]) & (frames <= WAIT[1])
        held = tracks[during]
        ids = np.unique(held[held > 0])
        cover = float((held > 0).mean()) if held.size else 0.0
        out.append({
            "vehicle": v,
            "tracks_during_wait": int(ids.size),
            "wait_coverage": round(cover, 3),
            "keeps_id": bool(ids.size == 1 and cover >= COVER),
        })
    return out


def _spurious_causes(run: SceneRun) -> dict[str, int]:
    """Spurious tracks by likely cause, from where they sit relative to vehicles and poles."""
    ids, obj, _ = run.match.majority(MIN_ASSOC)
    cols = run.log.columns()
    poles = np.asarray(run.scene.meta.get("poles", []), float).reshape(-1, 2)
    causes = {"split or duplicate of a vehicle": 0, "pole (camera jitter)": 0, "other": 0}
    for t in ids[obj == 0].tolist():  # a handful of tracks, offline analysis
        sel = cols["track_id"] == t
        xy, fr = cols["filtered_xy"][sel], cols["frame"][sel]
        if poles.size and np.median(np.min(np.linalg.norm(
                xy[:, None] - poles[None], axis=2), axis=1)) < 8.0:
            causes["pole (camera jitter)"] += 1
            continue
        near = []
        for f, p in zip(fr.tolist(), xy, strict=True):
            rs = run.scene.rows(f)
            g = run.scene.xy[rs][run.scene.visible[rs]]
            near.append(np.min(np.linalg.norm(g - p, axis=1)) if g.size else np.inf)
        if np.median(near) < 20.0:
            causes["split or duplicate of a vehicle"] += 1
        else:
            causes["other"] += 1
    return causes


def _score(run: SceneRun) -> dict[str, float]:
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))
    m = evaluate(MotTable.from_rows(run.scene.gt_mot()), pred, with_hota=False)
    return {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW", "FP", "FN")}


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Track X5 renderings with seeds ``seed, seed+1, ...`` (default 3 runs)."""
    n_runs = 3 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be at least 1, got {n_runs}")
    names = ("kalman-ca", "rls", "default")
    tracked = {n: {c: 0 for c in CATEGORIES} for n in names}
    tracked_spec = {n: {c: 0 for c in CATEGORIES} for n in names}
    spurious_spec = {n: [] for n in names}
    scores_spec = {n: [] for n in names}
    totals = {c: 0 for c in CATEGORIES}
    keeps = {n: {"templates": 0, "no_templates": 0, "templates_ncc_0.7": 0} for n in names}
    n_waiting = 0
    spurious = {n: [] for n in names}
    causes = {n: {} for n in names}
    scores = {n: [] for n in names}
    fps = {n: [] for n in names}
    per_run: list[dict[str, Any]] = []
    plot_runs: dict[str, SceneRun] = {}
    for r in range(n_runs):
        s = seed + r
        scene = x5_intersection(s)
        frames = None
        entry: dict[str, Any] = {"seed": s}
        for c in CATEGORIES:
            totals[c] += int(scene.ids_of(c).size)
        n_waiting += int(scene.ids_of("waiting").size)
        from mvtrack.sim.render import render_frames

        frames = list(render_frames(scene, s))
        for name, cfg in _configs(scene).items():
            with_t = track_scene(scene, cfg, seed=s, frames=frames, templates=True)
            without = track_scene(scene, cfg, seed=s, frames=frames, templates=False)
            spec = track_scene(scene, cfg, seed=s, frames=frames, templates=True,
                               detector_params=SPEC_BLOBS)
            summ = summarise(with_t, MIN_ASSOC)
            summ_spec = summarise(spec, MIN_ASSOC)
            cov, cov_spec = summ["coverage"], summ_spec["coverage"]
            for c in CATEGORIES:
                ids_c = scene.ids_of(c).tolist()
                tracked[name][c] += sum(1 for v in ids_c if cov[v]["coverage"] >= COVER)
                tracked_spec[name][c] += sum(
                    1 for v in ids_c if cov_spec[v]["coverage"] >= COVER
                )
            spurious_spec[name].append(summ_spec["spurious"])
            scores_spec[name].append(_score(spec))
            loose = track_scene(scene, cfg, seed=s, frames=frames, templates=True,
                                template_params={"min_score": LOOSE_NCC})
            w_t, w_n, w_l = _waiting(with_t), _waiting(without), _waiting(loose)
            keeps[name]["templates_ncc_0.7"] += sum(w["keeps_id"] for w in w_l)
            keeps[name]["templates"] += sum(w["keeps_id"] for w in w_t)
            keeps[name]["no_templates"] += sum(w["keeps_id"] for w in w_n)
            spurious[name].append(summ["spurious"])
            for k, v in _spurious_causes(with_t).items():
                causes[name][k] = causes[name].get(k, 0) + v
            sc = _score(with_t)
            scores[name].append(sc)
            fps[name].append(with_t.result.fps)
            entry[name] = {
                "tracks": summ["tracks"], "spurious": summ["spurious"], "score": sc,
                "waiting_with_templates": w_t, "waiting_without_templates": w_n,
                "spec_blobs": {"tracks": summ_spec["tracks"], "spurious": summ_spec["spurious"],
                               "score": scores_spec[name][-1]},
                "coverage": {str(v): cov[v] for v in cov},
            }
            if r == 0:
                plot_runs[name] = with_t
        per_run.append(entry)

    def mean(name: str, key: str, table: dict[str, list[Any]] = scores) -> float:
        return round(float(np.mean([s[key] for s in table[name]])), 4)

    figures: dict[str, Any] = {
        "paper": PAPER,
        "runs": n_runs,
        "per_category": {
            n: {c: {"tracked": tracked[n][c], "total": totals[c]} for c in CATEGORIES}
            for n in names
        },
        "per_category_spec_blobs": {
            n: {c: {"tracked": tracked_spec[n][c], "total": totals[c]} for c in CATEGORIES}
            for n in names
        },
        "spec_blobs": {"detector_params": SPEC_BLOBS,
                       "mota": {n: mean(n, "MOTA", scores_spec) for n in names},
                       "idf1": {n: mean(n, "IDF1", scores_spec) for n in names},
                       "spurious_tracks": spurious_spec},
        "detector_params": resolve_settings(RunSettings(), (320, 240)).detector_params,
        "waiting_keep_id": {n: keeps[n] | {"total": n_waiting} for n in names},
        "spurious_tracks": {n: spurious[n] for n in names},
        "spurious_causes": causes,
        "mota": {n: mean(n, "MOTA") for n in names},
        "idf1": {n: mean(n, "IDF1") for n in names},
        "idsw": {n: mean(n, "IDSW") for n in names},
        "ms_per_frame": {n: round(1000.0 / float(np.median(fps[n])), 2) for n in names},
        "per_run": per_run,
    }
    rows: list[list[Any]] = []
    for c in CATEGORIES:
        rows.append([
            f"{c}: one track ≥ 80 % of visible frames",
            "all" if c != "waiting" else "tracked (2)",
            *(f"{tracked[n][c]}/{totals[c]}" for n in names),
        ])
    rows.append(["all moving vehicles tracked, SPEC blob stage (no closing, area ≥ 20)", "all",
                 *(f"{sum(tracked_spec[n][c] for c in CATEGORIES[:3])}/"
                   f"{sum(totals[c] for c in CATEGORIES[:3])}" for n in names)])
    rows.append(["spurious tracks per run, SPEC blob stage (median)", "some (> 0)",
                 *(f"{np.median(spurious_spec[n]):g}" for n in names)])
    rows.append(["waiting vehicles keep their ID (template matching)", "—",
                 *(f"{keeps[n]['templates']}/{n_waiting}" for n in names)])
    rows.append(["waiting vehicles keep their ID (no template matching)", "—",
                 *(f"{keeps[n]['no_templates']}/{n_waiting}" for n in names)])
    rows.append([f"waiting vehicles keep their ID (template matching, NCC ≥ {LOOSE_NCC})", "—",
                 *(f"{keeps[n]['templates_ncc_0.7']}/{n_waiting}" for n in names)])
    rows.append(["spurious tracks per run (median)", "some (> 0)",
                 *(f"{np.median(spurious[n]):g}" for n in names)])
    rows.append(["MOTA (mean over runs)", "—", *(figures["mota"][n] for n in names)])
    rows.append(["IDF1 (mean over runs)", "—", *(figures["idf1"][n] for n in names)])
    rows.append(["ms per frame (detect + track)", "< 33", *(figures["ms_per_frame"][n]
                                                            for n in names)])
    notes = f"""
Setup: {n_runs} renderings (seeds {seed}–{seed + n_runs - 1}) of the SPEC §5 X5 scene, each
tracked by paper 1's system (20 px circular gate, non-exclusive nearest, warm-up) with the CA
Kalman filter and with RLS, and by the `default` preset as `mvtrack track` uses it.
Detection: disturbance map (T = 25, β_min = 0.02) with the
pipeline's blob stage (7×7 closing, area ≥ 40 px: `mvtrack.pipeline.resolve_settings`), and
for comparison the SPEC §1.1 [R] blob stage (opening only, area ≥ 20 px), under which the
two tones of a vehicle and the jitter-flickering edges of a standing vehicle become separate
blobs and, with non-exclusive association, separate tracks — paper 1's "segmentation splits
vehicles by colour", much amplified. Results rows leave out coasting predictions. Template matching
for stopped vehicles (`StoppedVehicleRescuer`: NCC ≥ 0.8 inside the gate, only for tracks that
have moved ≥ 10 px, at their last measured place, with no detection covering the match).
Counts pair output rows with the visible ground truth per frame (Hungarian on centre
distance ≤ max(6 px, 0.75 × box size)); a vehicle is tracked when one track holds ≥ 80 % of
its visible frames. Spurious: tracks with ≥ {MIN_ASSOC} associations paired with no vehicle
in most of their frames, sorted by where they sit (pole, beside a vehicle, elsewhere).
Template matching uses SPEC §1.1 [R]'s NCC ≥ 0.8; the variant with NCC ≥ {LOOSE_NCC} is
reported because under this scene's noise and sub-pixel jitter the NCC of a standing
vehicle against its last detected appearance hovers around 0.75–0.82.
MOTA/IDF1 use IoU ≥ 0.5 on the boxes, which is strict for 16×9 px vehicles whose blob box
includes part of the disturbance-map trail. Times are medians on a shared 2-core machine.
"""
    plots = {n: trajectory_plot(plot_runs[n], f"X5, {n}, seed {seed}") for n in names}
    return Report(
        name="intersection",
        title="X5 — paper 1 intersection (reconstructed): vehicles tracked per category",
        figures=figures,
        columns=["quantity", "paper", "KF (kalman-ca)", "RLS", "modern default"],
        rows=rows,
        notes=notes,
        plots=plots,
    )
