"""X8's report: the notes, the outcome bars and the split figure."""

from __future__ import annotations

from typing import Any

from mvtrack.experiments._video import SceneRun
from mvtrack.experiments.splitting_group_measure import (
    AFTER,
    BEFORE,
    DISTANCES,
    HOLD,
    ISOLATION_PX,
    LABELS,
    NO_DEPTH,
    OUTCOMES,
)
from mvtrack.experiments.stats import fmt_rate


def group_name(v: int) -> str:
    return {1: "P1 (diagonal walker)", 2: "P2", 3: "P3"}.get(v, "other targets")


def latency(v: dict[str, Any]) -> str:
    return "—" if v["median"] is None else f"{v['median']:g} ({v['max']})"


def report_notes(fig: dict[str, Any], summary: dict[str, Any], n_runs: int, seed: int) -> str:
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
{latency(u['latency_frames'])}, {latency(c['latency_frames'])} and {latency(m['latency_frames'])}
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


def outcome_plot(summary: dict[str, Any]) -> Any:
    from matplotlib.figure import Figure

    from mvtrack.viz.colors import FAILURE_COLOR, PALETTE
    from mvtrack.viz.plots import grouped_bars

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


def split_plot(runs: dict[str, SceneRun], p1: dict[str, dict[str, Any]]) -> Any:
    """The split close up, seed 0: truth of P1–P3 beside the group's track(s) and P1's."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from mvtrack.viz.colors import FAILURE_COLOR, PALETTE, TRUTH_COLOR, halo

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
