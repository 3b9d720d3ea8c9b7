"""X8: paper 2's group of three people splitting behind a car (Fig. 4, SPEC §5 X8).

The scene (:func:`mvtrack.sim.scenes.x8_splitting_group`: 320×240, 15 fps, 240 frames; P1-P3
walk together from the upper left, merge into one blob, split at frame 60 behind a static white
car; P1 walks diagonally to the right-middle, P2 and P3 go down; eleven other targets) is
rendered and run through the whole pipeline with paper 2's tracker
(:func:`mvtrack.tracking.paper2`: independent per-axis CA Kalman filters, R = 4 px², q = 0.05,
non-exclusive nearest, warm-up) under three association distances: eq. (9) of paper 2
(``uncoupled``), the corrected x-y coupled region (``coupled``, SPEC §2.3, ρ = 2) and the full
Mahalanobis distance (``mahalanobis``), each with its χ² gate 9.21. The modern default is run
for reference.

Measured per run: whether P1 gets his own track (one track holding ≥ 90 % of his visible
frames after the split, and that track follows him more than P2 or P3); the latency from his
first isolated frame (visible, ≥ 12 px from P2 and P3) until that track is on him; ID
switches (motmetrics, whole scene) and P1's own track changes after the split; the number of
tracks with ≥ 5 associations.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments._video import (
    SceneRun,
    breaks,
    default_config,
    summarise,
    track_scene,
    trajectory_plot,
)
from mvtrack.experiments.report import Report
from mvtrack.sim.scenes import x8_splitting_group
from mvtrack.tracking import paper2

DISTANCES = ("uncoupled", "coupled", "mahalanobis")
PAPER = {
    "targets": 14,
    "uncoupled": "fails on the diagonal walker P1",
    "coupled": "tracks P1 immediately after the split",
}
HOLD = 0.9
ISOLATION_PX = 12.0
MIN_ASSOC = 5


def _configs(scene: Any) -> dict[str, Any]:
    fps = scene.fps
    out: dict[str, Any] = {d: paper2(d, fps=fps) for d in DISTANCES}
    out["default"] = default_config(scene)
    return out


def p1_result(run: SceneRun) -> dict[str, Any]:
    """P1 after the split: own track, its share of his frames, latency, track changes."""
    scene = run.scene
    split = int(scene.meta.get("split_frame", 60))
    p1, others = 1, (2, 3)
    frames, tracks = run.match.sequence(p1)
    after = frames >= split
    f1, t1 = frames[after], tracks[after]
    out: dict[str, Any] = {"own_track": False, "hold": 0.0, "latency": None,
                           "track_changes": 0, "first_isolated": None,
                           "group_track_continues": False}
    before = tracks[(frames < split) & (tracks > 0)]
    group_track = int(np.bincount(before).argmax()) if before.size else -1
    if f1.size == 0:
        return out
    # first isolated frame: visible and at least ISOLATION_PX from the other two
    fa, xa = scene.trajectory(p1)
    dist = np.full(fa.size, np.inf)
    for o in others:
        fo, xo = scene.trajectory(o)
        _, ia, io = np.intersect1d(fa, fo, return_indices=True)
        dist[ia] = np.minimum(dist[ia], np.linalg.norm(xa[ia] - xo[io], axis=1))
    iso_frames = fa[(dist >= ISOLATION_PX) & (fa >= split)]
    iso_frames = iso_frames[np.isin(iso_frames, f1)]
    first_iso = int(iso_frames[0]) if iso_frames.size else None
    out["first_isolated"] = first_iso
    held = t1[t1 > 0]
    if held.size == 0:
        return out
    ids, counts = np.unique(held, return_counts=True)
    best = int(ids[counts.argmax()])
    hold = float(counts.max() / f1.size)
    # "his own": the best track is paired with P1 more than with P2 or P3
    on = {o: int(np.sum(run.match.sequence(o)[1] == best)) for o in (p1, *others)}
    own = on[p1] > max(on[o] for o in others)
    out["hold"] = round(hold, 3)
    out["own_track"] = bool(own and hold >= HOLD)
    out["best_track"] = best
    out["track_changes"] = len(breaks(f1, t1))
    out["group_track_continues"] = bool(own and hold >= HOLD and best == group_track)
    if first_iso is not None:
        on_him = f1[(t1 == best) & (f1 >= first_iso)]
        if on_him.size:
            out["latency"] = int(on_him[0] - first_iso)
    return out


def _score(run: SceneRun) -> dict[str, float]:
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))
    m = evaluate(MotTable.from_rows(run.scene.gt_mot()), pred, with_hota=False)
    return {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW")}


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Track X8 renderings with seeds ``seed, seed+1, ...`` (default 5 runs)."""
    from mvtrack.sim.render import render_frames

    n_runs = 5 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be at least 1, got {n_runs}")
    names = (*DISTANCES, "default")
    res: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
    per_run: list[dict[str, Any]] = []
    plot_runs: dict[str, SceneRun] = {}
    for r in range(n_runs):
        s = seed + r
        scene = x8_splitting_group(s)
        frames = list(render_frames(scene, s))
        entry: dict[str, Any] = {"seed": s}
        for name, cfg in _configs(scene).items():
            tr = track_scene(scene, cfg, seed=s, frames=frames)
            item = {"p1": p1_result(tr), "tracks": summarise(tr, MIN_ASSOC)["tracks"],
                    "score": _score(tr)}
            res[name].append(item)
            entry[name] = item
            if r == 0:
                plot_runs[name] = tr
        per_run.append(entry)

    def count_own(n: str) -> int:
        return sum(x["p1"]["own_track"] for x in res[n])

    def med_latency(n: str) -> float | None:
        lat = [x["p1"]["latency"] for x in res[n] if x["p1"]["own_track"]]
        return float(np.median(lat)) if lat else None

    def mean(n: str, key: str) -> float:
        return round(float(np.mean([x["score"][key] for x in res[n]])), 4)

    figures: dict[str, Any] = {
        "paper": PAPER,
        "runs": n_runs,
        "p1_own_track": {n: count_own(n) for n in names},
        "p1_hold_median": {n: float(np.median([x["p1"]["hold"] for x in res[n]])) for n in names},
        "latency_frames_median": {n: med_latency(n) for n in names},
        "p1_track_changes": {n: [x["p1"]["track_changes"] for x in res[n]] for n in names},
        "idsw": {n: mean(n, "IDSW") for n in names},
        "tracks": {n: float(np.median([x["tracks"] for x in res[n]])) for n in names},
        "mota": {n: mean(n, "MOTA") for n in names},
        "idf1": {n: mean(n, "IDF1") for n in names},
        "per_run": per_run,
    }

    def lat_text(n: str) -> str:
        v = med_latency(n)
        return "—" if v is None else f"{v:g} frame" + ("" if v == 1 else "s")

    rows = [
        ["P1 gets his own track (≥ 90 % after the split)", "(9) no; (10) yes",
         *(f"{count_own(n)}/{n_runs}" for n in names)],
        ["... and it is the group's track, continued", "(10) yes",
         *(f"{sum(x['p1']['group_track_continues'] for x in res[n])}/{n_runs}" for n in names)],
        ["P1's best track holds (median share)", "—",
         *(f"{figures['p1_hold_median'][n]:.2f}" for n in names)],
        ["latency after his first isolated frame (median)", "(10): immediately",
         *(lat_text(n) for n in names)],
        ["P1 track changes after the split (per run)", "—",
         *(", ".join(map(str, figures["p1_track_changes"][n])) for n in names)],
        ["ID switches, whole scene (mean)", "—", *(figures["idsw"][n] for n in names)],
        ["tracks with ≥ 5 associations (median; 14 targets)", "—",
         *(f"{figures['tracks'][n]:g}" for n in names)],
        ["MOTA (mean)", "—", *(figures["mota"][n] for n in names)],
        ["IDF1 (mean)", "—", *(figures["idf1"][n] for n in names)],
    ]
    same = all(
        [x["p1"] for x in res[d]] == [x["p1"] for x in res[DISTANCES[0]]] for d in DISTANCES
    )
    group_kept = {d: sum(x["p1"]["group_track_continues"] for x in res[d]) for d in names}
    figures["p1_keeps_group_track"] = group_kept
    verdict = (
        "All three gates give the same P1 figures in every run: the association distance "
        "does not decide anything in this scene. "
        if same else "The gates differ in at least one run (see per_run). "
    )
    verdict += (
        "The group's track continues onto P1 after the split in "
        + ", ".join(f"{group_kept[d]}/{n_runs} runs with {d}" for d in names)
        + "; otherwise P1 is picked up by a new track. The static car hides the whole group "
        "for several frames, and while the merged blob slides behind it its centroid stalls, "
        "so the group's track is lost at the car (or its prediction no longer reaches the "
        "people) whatever the gate. Paper 2 reports that eq. (10) picks P1 up immediately "
        "after the split and eq. (9) does not; here every gate picks him up within a frame or "
        "two, with a new track."
    )
    notes = f"""
Setup: {n_runs} renderings (seeds {seed}–{seed + n_runs - 1}) of the SPEC §5 X8 scene, disturbance
map with the pipeline's blob stage (7×7 closing, area ≥ 40 px), paper 2's tracker
(`paper2(distance)`: per-axis CA Kalman filters with R = 4 px², q = 0.05, non-exclusive nearest,
χ² gate 9.21, warm-up) with eq. (9) (`uncoupled`), the corrected coupled region (`coupled`,
SPEC §2.3, ρ = 2) and `mahalanobis`; the modern default for reference. P1's frames after the
split are his visible frames from frame 60 on; his track is "his own" when one track holds
≥ 90 % of them and follows him more than P2 or P3. Latency counts frames from his first
isolated frame (visible, ≥ {ISOLATION_PX:g} px from P2 and P3) to the first frame that track is
paired with him. Identical per-axis filters give P̄x = P̄y, so eq. (9) is a circle (E2.3); the
coupled region stretches it ρ = 2 times along the predicted velocity.

{verdict}
"""
    plots = {n: trajectory_plot(plot_runs[n], f"X8, {n}, seed {seed}") for n in names}
    return Report(
        name="splitting-group",
        title="X8 — paper 2 splitting group: eq. (9) vs coupled region vs Mahalanobis",
        figures=figures,
        columns=["quantity", "paper", "eq. (9) uncoupled", "coupled (SPEC §2.3)", "Mahalanobis",
                 "modern default"],
        rows=rows,
        notes=notes,
        plots=plots,
    )
