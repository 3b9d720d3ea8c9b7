"""X8: paper 2's group of three people splitting behind a car (Fig. 4, SPEC §5 X8 as revised).

The scene (:func:`mvtrack.sim.splitting_group.x8_splitting_group`: 320×240, 15 fps, 240 frames, 14
targets) has P1–P3 walk together from the upper left as one blob and split at frame 60 at a
parked white car, which hides at most the lower half of each person behind it, so the group's
blob is detected in every frame and its track lives through the split. P1 walks diagonally to
the right-middle, P2 and P3 go down. It is rendered and run through the whole pipeline: the
disturbance map of SPEC §1.1 [R] (3×3 opening, area ≥ 20 px, no closing) and paper 2's tracker
(:func:`mvtrack.tracking.paper2`: independent per-axis CA Kalman filters, R = 4 px², q = 0.05,
non-exclusive nearest, warm-up) under three association distances, each with its χ² gate
9.21: eq. (9) of paper 2 (``uncoupled``), the corrected x-y coupled region of eq. (10)
(``coupled``, SPEC §2.3, ρ = 2) and the full Mahalanobis distance (``mahalanobis``). The
modern default runs as a variant.

Measured per seed (SPEC X8: ≥ 50 seeds): the group's track (the track on the merged blob in
the 15 frames before the split) and on whom it continues once P1 walks alone (P1, P2, P3, or it
ends: the person it follows in most of the 15 frames after P1's first isolated frame); whether
P1 gets a track that follows him in ≥ 90 % of his remaining visible frames; the latency from
his first isolated frame (visible, ≥ 12 px from P2 and P3) to the first frame that track is on
him; ID switches (motmetrics, whole scene); the number of tracks with ≥ 5 associations. Rates
come with 95 % Wilson intervals, and every distance is compared with eq. (9) on the same seeds
(exact McNemar test).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.experiments._video import (
    SceneRun,
    default_config,
    pipeline_blob_params,
    summarise,
    track_scene,
    trajectory_plot,
)
from mvtrack.experiments.report import Report
from mvtrack.experiments.stats import fmt_rate, paired, rate, rate_of
from mvtrack.sim.splitting_group import x8_splitting_group
from mvtrack.tracking import paper2

DISTANCES = ("uncoupled", "coupled", "mahalanobis")
LABELS = {"uncoupled": "eq. (9)", "coupled": "eq. (10), corrected (SPEC §2.3)",
          "mahalanobis": "Mahalanobis", "default": "modern default (variant)"}
PAPER = {
    "targets": 14,
    "uncoupled": "fails on the diagonal walker P1",
    "coupled": "tracks P1 immediately after the split",
}
#: the blob stage exactly as SPEC §1.1 [R] (3×3 opening, area ≥ 20 px, no closing)
SPEC_BLOBS = {"close_size": 0, "min_area": 20.0}
HOLD = 0.9
ISOLATION_PX = 12.0
#: frames before the split over which the group's track is identified, and after P1's first
#: isolated frame over which it is followed
BEFORE, AFTER = 15, 15
MIN_ASSOC = 5
DEFAULT_RUNS = 50
OUTCOMES = ("P1", "P2", "P3", "ends")


#: the [R] geometry's variant: the car hides the lower half of everyone over it (no depth order)
NO_DEPTH = "car without depth order"


def _configs(scene: Any) -> dict[str, dict[str, Any]]:
    fps = scene.fps
    out = {d: {"config": paper2(d, fps=fps), "detector_params": SPEC_BLOBS} for d in DISTANCES}
    out["default"] = {"config": default_config(scene),
                      "detector_params": pipeline_blob_params(scene.size)}
    return out


def _scenes(seed: int) -> dict[str, Any]:
    """The scene as specified, and the variant geometry."""
    return {"": x8_splitting_group(seed), NO_DEPTH: x8_splitting_group(seed, car_depth=False)}


def first_isolated(scene: Any, split: int) -> int | None:
    """P1's first visible frame from the split on that is ≥ ISOLATION_PX from P2 and P3."""
    fa, xa = scene.trajectory(1)
    dist = np.full(fa.size, np.inf)
    for o in (2, 3):
        fo, xo = scene.trajectory(o)
        _, ia, io = np.intersect1d(fa, fo, return_indices=True)
        dist[ia] = np.minimum(dist[ia], np.linalg.norm(xa[ia] - xo[io], axis=1))
    vis = scene.visible[scene.id == 1]
    ok = (dist >= ISOLATION_PX) & (fa >= split) & vis
    return int(fa[ok][0]) if ok.any() else None


def group_tracks(run: SceneRun, split: int) -> dict[int, int]:
    """Tracks on the merged blob before the split -> the frames (of the last BEFORE) each
    follows one of P1–P3. Under the non-exclusive nearest rule several tracks can ride it."""
    votes: dict[int, set[int]] = {}
    for p in (1, 2, 3):
        ids, _, _ = run.match.followers(p, (split - BEFORE, split - 1))
        for t in ids.tolist():
            votes.setdefault(t, set()).add(p)
    cols = run.log.columns()
    out = {}
    for t in votes:  # frames the track is output in the window and follows a group member
        sel = (cols["track_id"] == t) & (cols["frame"] >= split - BEFORE) & (cols["frame"] < split)
        out[t] = int(sel.sum())
    return out


def group_track(run: SceneRun, split: int) -> int:
    """The track on the merged blob: it follows P1–P3 in most of the frames before the split
    (the oldest such track on a tie)."""
    votes = group_tracks(run, split)
    return max(sorted(votes), key=lambda t: votes[t]) if votes else -1


def _continues_on(run: SceneRun, track: int, iso: int) -> tuple[str, list[int]]:
    on = []
    for p in (1, 2, 3):
        ids, counts, _ = run.match.followers(p, (iso, iso + AFTER - 1))
        on.append(int(counts[ids == track].sum()))
    return (OUTCOMES[int(np.argmax(on))] if max(on) > 0 else "ends"), on


def p1_result(run: SceneRun) -> dict[str, Any]:
    """On whom the group's track continues, and P1's own track after the split."""
    scene = run.scene
    split = int(scene.meta.get("split_frame", 60))
    iso = first_isolated(scene, split)
    g = group_track(run, split)
    out: dict[str, Any] = {"group_track": g, "first_isolated": iso, "continues_on": "ends",
                           "own_track": False, "hold": 0.0, "latency": None,
                           "group_track_is_p1s": False}
    if iso is not None and g > 0:
        out["continues_on"], on = _continues_on(run, g, iso)
        out["group_track_frames_on"] = dict(zip(OUTCOMES[:3], on, strict=True))
        riders = [t for t, n in group_tracks(run, split).items() if n >= BEFORE // 2]
        out["all_group_tracks_continue_on"] = {
            str(t): _continues_on(run, t, iso)[0] for t in sorted(riders)}
    if iso is not None and g > 0:
        out |= _offsets(run, g, iso)
    last = scene.n_frames - 1
    best, hold = run.match.followed_share(1, (split, last))
    out["best_track"], out["hold"] = best, round(hold, 3)
    out["own_track"] = bool(hold >= HOLD)
    out["group_track_is_p1s"] = bool(out["own_track"] and best == g)
    if iso is not None and best > 0:  # first frame from his isolation on that track is on him
        cols = run.log.columns()
        sel = (cols["track_id"] == best) & (cols["frame"] >= iso)
        fr, xy = cols["frame"][sel], cols["filtered_xy"][sel]
        f1, x1 = scene.trajectory(1)
        pos = np.searchsorted(f1, fr)
        ok = pos < f1.size
        ok[ok] = f1[pos[ok]] == fr[ok]
        r = max(6.0, 0.75 * 16.0)  # the pairing radius of a person's box
        near = ok.copy()
        near[ok] = np.linalg.norm(xy[ok] - x1[pos[ok]], axis=1) <= r
        if near.any():
            out["latency"] = int(fr[near][0] - iso)
    return out


def _offsets(run: SceneRun, g: int, iso: int) -> dict[str, Any]:
    """Where P1 and P2/P3 are, at P1's first isolated frame, from the group track's gate
    centre: P1's offset along and across the track's velocity, and both distances (px)."""
    cols = run.log.columns()
    sel = (cols["track_id"] == g) & (cols["frame"] == iso)
    if not sel.any():
        return {}
    c = cols["predicted_xy"][sel][0]
    v = cols["velocity"][sel][0]
    u = v / max(float(np.hypot(*v)), 1e-9)
    p = {k: run.scene.xy[(run.scene.frame == iso) & (run.scene.id == k)][0] for k in (1, 2, 3)}
    d1 = p[1] - c
    return {
        "p1_offset_along": round(float(d1 @ u), 2),
        "p1_offset_across": round(float(d1[0] * -u[1] + d1[1] * u[0]), 2),
        "p1_distance": round(float(np.hypot(*d1)), 2),
        "p2_p3_distance": round(float(min(np.hypot(*(p[2] - c)), np.hypot(*(p[3] - c)))), 2),
        "track_heading_deg": round(float(np.degrees(np.arctan2(v[1], v[0]))), 1),
    }


def _score(run: SceneRun) -> dict[str, float]:
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))
    m = evaluate(MotTable.from_rows(run.scene.gt_mot()), pred, with_hota=False)
    return {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW")}


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Track X8 renderings with seeds ``seed, seed+1, ...`` (default 50 runs)."""
    from mvtrack.sim.render import render_frames

    n_runs = DEFAULT_RUNS if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be at least 1, got {n_runs}")
    geo = [f"{d}, {NO_DEPTH}" for d in DISTANCES]
    names = (*DISTANCES, "default", *geo)
    res: dict[str, list[dict[str, Any]]] = {n: [] for n in names}
    plot_runs: dict[str, SceneRun] = {}
    for r in range(n_runs):
        s = seed + r
        for tag, scene in _scenes(s).items():
            frames = list(render_frames(scene, s))
            for name, opts in _configs(scene).items():
                if tag and name == "default":
                    continue
                key = f"{name}, {tag}" if tag else name
                tr = track_scene(scene, opts["config"], seed=s, frames=frames,
                                 detector_params=opts["detector_params"])
                res[key].append({"seed": s, "p1": p1_result(tr), "score": _score(tr),
                                 "tracks": summarise(tr, MIN_ASSOC)["tracks"]})
                if r == 0 and not tag:
                    plot_runs[name] = tr

    def outcome(n: str, key: str) -> NDArray[np.bool_]:
        return np.array([x["p1"]["continues_on"] == key for x in res[n]])

    summary: dict[str, Any] = {}
    for n in names:
        own = np.array([x["p1"]["own_track"] for x in res[n]])
        lat = [x["p1"]["latency"] for x in res[n] if x["p1"]["own_track"]
               and x["p1"]["latency"] is not None]
        summary[n] = {
            "continues_on": {k: rate_of(outcome(n, k)) for k in OUTCOMES},
            "any_group_track_continues_on_p1": rate_of(
                ["P1" in x["p1"].get("all_group_tracks_continue_on", {}).values()
                 for x in res[n]]),
            "group_tracks_median": float(np.median(
                [len(x["p1"].get("all_group_tracks_continue_on", {})) for x in res[n]])),
            "p1_own_track": rate_of(own),
            "p1_own_track_is_the_group_track": rate_of(
                [x["p1"]["group_track_is_p1s"] for x in res[n]]),
            "p1_hold_median": float(np.median([x["p1"]["hold"] for x in res[n]])),
            "latency_frames": {
                "median": float(np.median(lat)) if lat else None,
                "max": int(max(lat)) if lat else None,
                "immediate": rate(sum(1 for v in lat if v == 0), len(lat)),
                "values": lat,
            },
            "at_isolation_median": {
                k: float(np.median([x["p1"][k] for x in res[n] if k in x["p1"]]))
                for k in ("p1_offset_along", "p1_offset_across", "p1_distance",
                          "p2_p3_distance", "track_heading_deg")
                if any(k in x["p1"] for x in res[n])},
            "idsw_mean": float(np.mean([x["score"]["IDSW"] for x in res[n]])),
            "tracks_median": float(np.median([x["tracks"] for x in res[n]])),
            "mota_mean": float(np.mean([x["score"]["MOTA"] for x in res[n]])),
            "idf1_mean": float(np.mean([x["score"]["IDF1"] for x in res[n]])),
        }
    vs9 = {}
    for d in (*DISTANCES[1:], "default"):
        mota = np.array([x["score"]["MOTA"] for x in res[d]])
        mota9 = np.array([x["score"]["MOTA"] for x in res["uncoupled"]])
        vs9[d] = {
            "group_track_continues_on_p1": paired(outcome(d, "P1"), outcome("uncoupled", "P1")),
            "p1_own_track": paired([x["p1"]["own_track"] for x in res[d]],
                                   [x["p1"]["own_track"] for x in res["uncoupled"]]),
            # exact sign test: seeds where its MOTA is above eq. (9)'s (only_a) or below
            "mota_sign_test": paired(mota > mota9, mota < mota9),
        }
    same = all([x["p1"] for x in res[d]] == [x["p1"] for x in res["uncoupled"]]
               for d in DISTANCES)
    figures: dict[str, Any] = {
        "paper": PAPER,
        "runs": n_runs,
        "seed": seed,
        "setting": {"blobs": SPEC_BLOBS, "gate_chi2": 9.21, "rho": 2.0, "r": 4.0, "q": 0.05,
                    "occluder": "car 44×22 at (96, 64) hides the lower half of people "
                    "behind it"},
        **{n: summary[n] for n in DISTANCES},
        "variants": {n: summary[n] for n in ("default", *geo)},
        "against_eq9_same_seeds": vs9,
        "identical_outcomes_for_all_distances": bool(same),
        "per_run": res,
    }
    rows: list[list[Any]] = []
    for k in OUTCOMES:
        paper = {"P1": "(10): yes; (9): no", "ends": "—"}.get(k, "—")
        rows.append([f"the group's track continues on {k}" if k != "ends" else
                     "the group's track ends (follows no one)", paper,
                     *(fmt_rate(summary[d]["continues_on"][k]) for d in DISTANCES)])
    rows += [
        ["tracks riding the group's blob before the split (median; non-exclusive rule)", "—",
         *(f"{summary[d]['group_tracks_median']:g}" for d in DISTANCES)],
        ["… any of them continues on P1", "—",
         *(fmt_rate(summary[d]["any_group_track_continues_on_p1"]) for d in DISTANCES)],
        ["P1 gets a track that follows him ≥ 90 % of his frames after the split",
         "(9): no; (10): yes", *(fmt_rate(summary[d]["p1_own_track"]) for d in DISTANCES)],
        ["… and it is the group's track", "(10): yes",
         *(fmt_rate(summary[d]["p1_own_track_is_the_group_track"]) for d in DISTANCES)],
        ["latency after his first isolated frame, median (max) frames", "(10): immediately",
         *(_lat(summary[d]["latency_frames"]) for d in DISTANCES)],
        ["… on him in his first isolated frame", "(10): yes",
         *(fmt_rate(summary[d]["latency_frames"]["immediate"]) for d in DISTANCES)],
        ["ID switches, whole scene (mean per seed)", "—",
         *(f"{summary[d]['idsw_mean']:.2f}" for d in DISTANCES)],
        ["tracks with ≥ 5 associations (median; 14 targets)", "14 targets",
         *(f"{summary[d]['tracks_median']:g}" for d in DISTANCES)],
        ["MOTA / IDF1 (mean)", "—",
         *(f"{summary[d]['mota_mean']:.3f} / {summary[d]['idf1_mean']:.3f}" for d in DISTANCES)],
    ]
    iso = [summary[d]["at_isolation_median"] for d in DISTANCES]
    rows.append(["at P1's first isolated frame (median): P1's offset from the group track's "
                 "gate centre along / across its velocity; P2 or P3's distance (px)", "—",
                 *(f"{v.get('p1_offset_along', float('nan')):.1f} / "
                   f"{v.get('p1_offset_across', float('nan')):.1f}; "
                   f"{v.get('p2_p3_distance', float('nan')):.1f}" for v in iso)])
    rows.append([f"variant *{NO_DEPTH}*: group's track on P1 / P2 / P3 / ends", "—",
                 *(" / ".join(f"{summary[g]['continues_on'][k]['k']}" for k in OUTCOMES)
                   + f" of {summary[g]['continues_on']['P1']['n']}" for g in geo)])
    rows.append([f"variant *{NO_DEPTH}*: P1 gets his own track", "—",
                 *(fmt_rate(summary[g]["p1_own_track"]) for g in geo)])
    dflt = summary["default"]
    rows.append(["variant *default*: group's track on P1 / P2 / P3 / ends; P1's own track", "—",
                 " / ".join(str(dflt["continues_on"][k]["k"]) for k in OUTCOMES)
                 + f" of {dflt['continues_on']['P1']['n']}; " + fmt_rate(dflt["p1_own_track"]),
                 "(one tracker)", ""])
    plots = {n: trajectory_plot(plot_runs[n], f"X8, {LABELS[n]}, seed {seed}",
                                group_of=_group_name, legend_title="track follows")
             for n in (*DISTANCES, "default")}
    plots["outcomes"] = _outcome_plot(summary)
    plots["split"] = _split_plot({d: plot_runs[d] for d in DISTANCES},
                                 {d: res[d][0]["p1"] for d in DISTANCES})
    return Report(
        name="splitting-group",
        title="X8 — paper 2 splitting group: on whom the group's track continues, by distance",
        figures=figures,
        columns=["quantity", "paper", "eq. (9) uncoupled", "eq. (10) coupled (SPEC §2.3)",
                 "Mahalanobis"],
        rows=rows,
        notes=_notes(figures, summary, n_runs, seed),
        plots=plots,
        variants={"default": "the modern default as `mvtrack track` uses it (its own blob "
                  "stage, global assignment), for reference",
                  NO_DEPTH: "the other reading of the revised geometry: the car hides the lower "
                  "half of everyone over it, also of people whose feet are already below its "
                  "lower edge (who are otherwise in front of it)"},
    )


def _group_name(v: int) -> str:
    return {1: "P1 (diagonal walker)", 2: "P2", 3: "P3"}.get(v, "other targets")


def _lat(v: dict[str, Any]) -> str:
    return "—" if v["median"] is None else f"{v['median']:g} ({v['max']})"


def _notes(fig: dict[str, Any], summary: dict[str, Any], n_runs: int, seed: int) -> str:
    u, c, m = (summary[d] for d in DISTANCES)
    iso = u["at_isolation_median"]
    g = {d: summary[f"{d}, {NO_DEPTH}"] for d in DISTANCES}
    t = fig["against_eq9_same_seeds"]["coupled"]["group_track_continues_on_p1"]
    st = fig["against_eq9_same_seeds"]["coupled"]["mota_sign_test"]
    top = {d: max(OUTCOMES, key=lambda k: summary[d]["continues_on"][k]["k"]) for d in DISTANCES}
    helps = c["continues_on"]["P1"]["k"] > u["continues_on"]["P1"]["k"] and t["p"] < 0.05
    verdict = (
        "The coupled region helps here: it continues the group's track on P1 significantly "
        "more often than eq. (9)."
        if helps else
        "The coupled region does not help here: it continues the group's track on P1 in "
        f"{fmt_rate(c['continues_on']['P1'])} of the seeds against "
        f"{fmt_rate(u['continues_on']['P1'])} for eq. (9) (seeds where only the coupled region "
        f"does: {t['only_a']}, only eq. (9): {t['only_b']}, exact McNemar p = {t['p']:.2g})."
    )
    same = ("All three distances give the same outcome in every seed. "
            if fig["identical_outcomes_for_all_distances"] else "")
    return f"""
Setup: {n_runs} renderings (seeds {seed}–{seed + n_runs - 1}) of the SPEC §5 X8 scene as
revised: the parked car (44×22 px at (96, 64)) hides at most the lower half of each person
behind it (people whose feet are below its lower edge are in front of it) [R, our geometry],
so the group is one detected blob in every frame up to the split and each person's upper half
is detected after it. Disturbance map with the SPEC §1.1 [R] blob stage (3×3 opening,
area ≥ 20 px, no closing); paper 2's tracker (`paper2(distance)`: per-axis CA Kalman filters
with R = 4 px², q = 0.05, non-exclusive nearest, χ² gate 9.21, warm-up) with eq. (9)
(`uncoupled`), the corrected coupled region (`coupled`, SPEC §2.3, ρ = 2) and `mahalanobis`.
The group's track is the track that follows P1–P3 in most of the {BEFORE} frames before the
split; it continues on the person it follows in most of the {AFTER} frames from P1's first
isolated frame (visible, ≥ {ISOLATION_PX:g} px from P2 and P3), and "ends" when it follows no
one then. A track follows a person in a frame when it is within max(6 px, 0.75 × 16 px) of him.
Intervals are 95 % Wilson intervals over the seeds.

**What happens.** The group's track lives through the split in every seed and continues on
{top['uncoupled']} with eq. (9) ({fmt_rate(u['continues_on'][top['uncoupled']])}), on
{top['coupled']} with the coupled region ({fmt_rate(c['continues_on'][top['coupled']])}) and on
{top['mahalanobis']} with Mahalanobis ({fmt_rate(m['continues_on'][top['mahalanobis']])}).
{same}Why: while the three are still one blob, two of them (P2, P3) walk down, so the blob's
centroid, which the group's track follows, bends down with them. At P1's first isolated frame
(median over seeds, eq. (9)) the track heads {iso['track_heading_deg']:.0f}° (the group walked
at 34°, P1 now walks at 18°, P2 and P3 at 80° and 96°; image y down), its gate centre is
{iso['p2_p3_distance']:.1f} px from P2 or P3, and P1 is {iso['p1_distance']:.1f} px from it,
{-iso['p1_offset_along']:.1f} px behind it along its velocity and
{abs(iso['p1_offset_across']):.1f} px across: outside every gate, and the coupled region, which
stretches the gate along the track's velocity, points at P2 and P3. The choice between the
people is made by the centroid of the merged blob before any gate sees two detections. P1 is
then picked up by a new track: he gets a track that follows him in ≥ {HOLD:.0%} of his
frames in {fmt_rate(u['p1_own_track'])} (eq. (9)), {fmt_rate(c['p1_own_track'])} (coupled)
and {fmt_rate(m['p1_own_track'])} (Mahalanobis) of the seeds, with a median latency of
{_lat(u['latency_frames'])}, {_lat(c['latency_frames'])} and {_lat(m['latency_frames'])}
frames (median (max)) after his first isolated frame.

The other reading of the geometry (variant *{NO_DEPTH}*: the car hides the lower half of
everyone over it) gives the same picture: the group's track continues on P1 in
{g['uncoupled']['continues_on']['P1']['k']}, {g['coupled']['continues_on']['P1']['k']} and
{g['mahalanobis']['continues_on']['P1']['k']} of {g['coupled']['continues_on']['P1']['n']} seeds
(eq. (9), coupled, Mahalanobis).

**Does the coupled region help?** {verdict} Over the whole scene (all 14 targets) its MOTA is
below eq. (9)'s in {st['only_b']} of {n_runs} seeds and above in {st['only_a']} (exact sign
test p = {st['p']:.2g}; why, we did not trace). Coupled against eq. (9):
{c['idsw_mean']:.2f} against {u['idsw_mean']:.2f} ID switches per seed, MOTA
{c['mota_mean']:.3f} against {u['mota_mean']:.3f}, IDF1 {c['idf1_mean']:.3f} against
{u['idf1_mean']:.3f} (Mahalanobis: {m['idsw_mean']:.2f}, {m['mota_mean']:.3f},
{m['idf1_mean']:.3f}). Paper 2 reports that eq. (9) loses P1 and eq. (10)
tracks him at once. On this reconstruction the second half holds for every distance (P1's new
track is on him at once) and the first for none: eq. (9) does not lose him, and no distance
continues the group's track on him.
"""


def _outcome_plot(summary: dict[str, Any]) -> Any:
    from matplotlib.figure import Figure

    from mvtrack.viz.plots import FAILURE_COLOR, PALETTE, grouped_bars

    fig = Figure(figsize=(11, 4.4), layout="constrained")
    left, right = fig.subplots(1, 2, gridspec_kw={"width_ratios": (1.6, 1.0)})
    names = list(DISTANCES)
    colors = {LABELS[d]: PALETTE[i] for i, d in enumerate(names)}
    series = {LABELS[d]: [summary[d]["continues_on"][k]["rate"] for k in OUTCOMES]
              for d in names}
    errors = {LABELS[d]: [summary[d]["continues_on"][k]["ci95"] for k in OUTCOMES]
              for d in names}
    grouped_bars(left, ["P1 (paper: (10))", "P2", "P3", "ends"], series, errors=errors,
                 colors=colors, fmt="{:.2f}")
    left.set(title="on whom the group's track continues after the split", ylim=(0, 1.15),
             ylabel="share of seeds (95 % Wilson intervals)")
    handles, labels = left.get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=8, loc="outside lower center", ncol=3)
    cats = ["P1 has his own track", "… the group's track", "on him at once"]
    series = {LABELS[d]: [summary[d]["p1_own_track"]["rate"],
                          summary[d]["p1_own_track_is_the_group_track"]["rate"],
                          summary[d]["latency_frames"]["immediate"]["rate"]] for d in names}
    errors = {LABELS[d]: [summary[d]["p1_own_track"]["ci95"],
                          summary[d]["p1_own_track_is_the_group_track"]["ci95"],
                          summary[d]["latency_frames"]["immediate"]["ci95"]] for d in names}
    grouped_bars(right, cats, series, errors=errors, colors=colors, fmt="{:.2f}")
    right.set(title="P1 after the split", ylim=(0, 1.15))
    right.tick_params(axis="x", labelsize=8)
    right.axhline(0, color=FAILURE_COLOR, lw=0.5)
    n = summary[names[0]]["continues_on"]["P1"]["n"]
    fig.suptitle(f"X8: {n} seed{'s' if n != 1 else ''} per distance")
    return fig


def _split_plot(runs: dict[str, SceneRun], p1: dict[str, dict[str, Any]]) -> Any:
    """The split close up, seed 0: truth of P1–P3 beside the group's track(s) and P1's."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from mvtrack.viz.plots import FAILURE_COLOR, PALETTE, TRUTH_COLOR, halo

    fig = Figure(figsize=(12, 4.6), layout="constrained")
    axes = fig.subplots(1, len(runs), sharey=True)
    lo, hi = 30, 100
    for ax, (name, run) in zip(axes, runs.items(), strict=True):
        scene = run.scene
        occ = scene.meta["occluders"][0]
        (cx, cy), (w, h) = occ["xy"], occ["wh"]
        ax.add_patch(Rectangle((cx - w / 2, cy - h / 2), w, h, facecolor="0.93",
                               edgecolor="0.5", label="parked car"))
        for k in (1, 2, 3):
            f, xy = scene.trajectory(k)
            sel = (f >= lo) & (f <= hi)
            ax.plot(xy[sel, 0], xy[sel, 1], ls=(0, (3, 2)), color=TRUTH_COLOR, lw=1.0,
                    label="truth P1–P3" if k == 1 else None)
            ax.annotate(f"P{k}", xy[f == 85][0], xytext=(4, 0), textcoords="offset points",
                        fontsize=8, path_effects=halo(2.5))
        cols = run.log.columns()
        res = p1[name]
        riders = [int(t) for t in res.get("all_group_tracks_continue_on", {})]
        g = res["group_track"]
        for t in riders:
            sel = (cols["track_id"] == t) & (cols["frame"] >= lo) & (cols["frame"] <= hi)
            main = t == g
            ax.plot(*cols["filtered_xy"][sel].T, "-", color=PALETTE[1] if main else FAILURE_COLOR,
                    lw=2.2 if main else 1.0, label=("the group's track" if main else
                                                    "other tracks on the group") if main or
                    t == next((r for r in riders if r != g), None) else None)
        best = res.get("best_track", -1)
        if best > 0:
            sel = (cols["track_id"] == best) & (cols["frame"] >= lo) & (cols["frame"] <= hi)
            ax.plot(*cols["filtered_xy"][sel].T, "-", color=PALETTE[0], lw=2.0,
                    label="P1's track")
        iso = res.get("first_isolated")
        if iso is not None:
            f, xy = scene.trajectory(1)
            ax.plot(*xy[f == iso][0], "*", color=PALETTE[0], ms=12, mec="black",
                    label=f"P1's first isolated frame ({iso})")
        ax.set(xlim=(40, 150), ylim=(115, 25), aspect="equal", xlabel="x (px)",
               title=f"{LABELS[name]}: continues on {res['continues_on']}")
    axes[0].set_ylabel("y (px)")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("X8, seed 0: the split close up (frames 30–100)")
    return fig

