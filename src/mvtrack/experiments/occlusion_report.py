"""X9's report: the notes and the figures (Figs. 9–11, the designs compared)."""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments.occlusion_measure import (
    HEADLINE,
    SEGMENTATION,
    TARGET_PX,
    WINDOW,
    PartMeasurements,
)
from mvtrack.sim.occlusion import OcclusionScene


def designs_plot(fig: dict[str, Any]) -> Any:
    """Maximum leg error of the default and of every variant (bars; grey where the [R]
    target is missed), beside the independent KFs' and the 7 px mark."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from mvtrack.viz.colors import FAILURE_COLOR, PALETTE

    runs = {"default (SPEC §3.3, our damping)": fig, **fig["variants"]}
    names = list(runs)
    y = np.arange(len(names))[::-1]
    mx = [runs[n]["skf_max_err"] for n in names]
    base = [runs[n]["baseline_max_err"] for n in names]
    colors = [PALETTE[2] if runs[n]["target_met"] else FAILURE_COLOR for n in names]
    out = Figure(figsize=(7.5, 0.42 * len(names) + 1.4), layout="constrained")
    ax = out.subplots()
    ax.barh(y, mx, color=colors, edgecolor="black", lw=0.6)
    ax.plot(base, y, "s", color=PALETTE[1], ms=5, label="independent KFs")
    ax.axvline(TARGET_PX, color="black", ls=":", label="[R] target 7 px")
    for yi, v in zip(y, mx, strict=True):
        ax.annotate(f"{v:.2f}", (v, yi), xytext=(3, 0), textcoords="offset points",
                    va="center", fontsize=7)
    ax.set_yticks(y, names, fontsize=8)
    ax.set_xlim(0, 1.12 * max(max(mx), max(base)))
    ax.set(xlabel="max leg error, k ∈ [115, 140] (px)",
           title="X9: the default and the other designs, same measurements")
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(facecolor=PALETTE[2], edgecolor="black", label="target met"),
                Patch(facecolor=FAILURE_COLOR, edgecolor="black", label="target not met")]
    ax.legend(handles=handles, fontsize=7, loc="lower right")
    return out


def report_notes(n_runs: int, fig: dict) -> str:
    v = fig["variants"]
    old = v["Q_r = Q_c"]
    sweep = fig["q_rel_sweep"]
    met = [k for k, s in sweep.items() if s["target_met"]]
    verdict = "met" if fig["target_met"] else "**not met**"

    def design(name: str) -> str:
        d = v[name]
        return (f"*{name}* {d['skf_max_err']:.2f} px"
                + (" (meets the mark)" if d["target_met"] else ""))

    spec_options = ", ".join(design(n) for n in (
        "1/Σ(1 − α^i)", "inferred from (15)", "coasting relation keeps its velocity"))
    ours = ", ".join(design(n) for n in ("coasting relation holds its offset",
                                         "cells before relations"))
    first = v["damping at unmatched ends only"]
    dsweep = fig["damping_sweep"]
    damps = ", ".join(f"d = {d} {r['skf_max_err']:.2f} px" for d, r in dsweep.items())
    d_met = [d for d, r in dsweep.items() if r["target_met"]]
    return f"""
Scene of SPEC X9 (320×240, 150 frames, legs partly hidden at t = 118–134 and fully at
t = 125–127, sensor noise σ = 2 grey levels), {n_runs} noise seed(s) from {fig['seed']};
errors are those of the predicted leg centre m_c^{{3−}}(k) against the true centre over
k ∈ [115, 140] (means over the seeds). The baseline is three independent KFs of the same model
and noise on the visible centroids, coasting when a part has < 5 visible pixels. The SKF runs
the SPEC §3.3 defaults: 6-D CA cells and relations, Q_c = 0.05·diag(0, 0, 0, 0, 1, 1),
Q_r = 0.01·Q_c (E3.12), R_c = 4 px², R_r = 8 px², inferred measurements from the relation
prior, 1/N_j; and one rule of ours that paper 3 has no counterpart for: a relation's velocity
and acceleration decay by d = 0.8 a frame while it gets no information (d^α with both ends
matched, α of the more occluded end; d with an unmatched end).

The [R] target (maximum error < {TARGET_PX:g} px, below the baseline, part 3 never lost) is
{verdict}: maximum error {fig['skf_max_err']:.2f} px at frame {fig['skf_max_err_frame']}
(worst seed {fig['skf_max_err_worst_seed']:.2f} px) against {fig['baseline_max_err']:.2f} px
for the independent KFs, RMS {fig['skf_rms_err']:.2f} against {fig['baseline_rms_err']:.2f}
px; the search box holds the legs in every frame. The first reconstruction (Q_r = Q_c,
damping at unmatched ends only) had {old['skf_max_err']:.1f} px; E3.12 brought that to
{first['skf_max_err']:.2f} px, the damping that follows α (below) to
{fig['skf_max_err']:.2f} px, {fig['baseline_max_err'] / fig['skf_max_err']:.1f}× better than
the baseline.

**Why the damping follows α.** Before the occlusion the legs swing from +2 to −2 px about the
torso, and the relation filter (even with Q_r = 0.01·Q_c) carries
{fig['relation_velocity_at_full_occlusion']:.2f} px/frame of that swing into the occlusion
(its prior velocity along x at frame 125, when the legs vanish). Our first reading damped a
relation only while an end was unmatched (t = 125–127). On the frames the legs reappear,
partly, α³ is still ≈ 1 (1 on the first, which has no previous features, E3.8), and eq. (15)
then measures the relation by the legs' own prediction, the loop the damping exists to break:
the velocity came back undamped and the legs' estimate drifted to
{first['skf_max_err']:.2f} px (variant *damping at unmatched ends only*, the previous default,
{abs(first['skf_max_err'] - TARGET_PX):.2f} px {'above' if first['skf_max_err'] >= TARGET_PX
else 'below'} the mark). An unmatched part is the limit α = 1 of the paper's own occlusion
measure (SPEC §3.3 "No match"), so the damping now follows α: d^α, the same d at α = 1 and
none at α = 0 (no occlusion: the SKF stays a set of independent KFs, X10). We found this
while looking for why X9 missed its mark; d itself is unchanged (sweep of d: {damps}; the
mark is met for d ∈ {{{", ".join(d_met)}}}).

**Other designs, same measurements.** The specification's own options and its literal reading
of a relation with an unmatched end: {spec_options}. Two more designs outside the
specification: {ours}; neither is adopted (a damping of 0 would set our constant to what
passes on this scene; running (13) before (15) reverses the order of SPEC §3.1 step 5 and
replaces the cell priors of eq. (15) by posteriors). The Q_r / Q_c sweep meets the mark for
{{{", ".join(met)}}} (`q_rel_sweep` and the plot).

α³ is 1 on every frame where the legs have no visible pixel and on the first frame after (no
previous features, E3.8), so its maximum is a plateau whose centre is reported. Parts by
segmentation (hue K-means tree inside the SKF search box, matched by least |ΔF|) give the same
measurements as the renderer's labels on this scene (variant *{SEGMENTATION}*).
"""


def report_plots(
    scene: OcclusionScene,
    meas: PartMeasurements,
    per: dict[str, list[dict]],
    sweep: dict[str, dict[str, Any]],
) -> dict:
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from mvtrack.viz.colors import FAILURE_COLOR, PALETTE, TRUTH_COLOR

    t = np.arange(meas.z.shape[0])
    spec, old, cv = per[HEADLINE][0], per["Q_r = Q_c"][0], per["CV model"][0]
    hidden = {"color": "0.85", "label": "legs fully hidden (125–127)"}
    fig9 = Figure(figsize=(7, 3.2), layout="constrained")
    ax = fig9.subplots()
    ax.axvspan(117.5, 134.5, color="0.94", label="legs partly hidden (118–134)")
    ax.axvspan(124.5, 127.5, **hidden)
    for k, name in enumerate(("head", "torso", "legs")):
        ax.plot(t, meas.alpha[:, k], color=PALETTE[k], lw=1.6 if k == 2 else 0.9,
                ls="-" if k == 2 else "--", label=f"α of part {k + 1} ({name})")
    ax.set(xlabel="frame k", ylabel="occlusion degree α(k), eq. (16)", xlim=(95, 149),
           ylim=(-0.03, 1.05), title="Fig. 9: occlusion degree of the parts")
    ax.legend(fontsize=7, loc="upper left")

    fig10 = Figure(figsize=(10, 5.6), layout="constrained")
    grid = fig10.add_gridspec(2, 2, height_ratios=(1.4, 1.0))
    axes = [fig10.add_subplot(grid[0, 0])]
    axes.append(fig10.add_subplot(grid[0, 1], sharey=axes[0]))
    weights = fig10.add_subplot(grid[1, :])
    for ax, run_, name in ((axes[0], spec, "Q_r = 0.01·Q_c (default)"),
                           (axes[1], old, "Q_r = Q_c (variant)")):
        skf = run_["_skf"]
        ax.axvspan(124.5, 127.5, **hidden)
        ax.plot(t, skf.own[:, 2], "-", color=PALETTE[0], label="2nd term: own measurement")
        ax.plot(t, skf.neighbours[:, 2], "--", color=PALETTE[1], label="3rd term: neighbours")
        ax.set(xlabel="frame k", title=name, xlim=(100, 149))
    axes[0].set_ylabel("‖term of eq. (13)‖, j = 3 (px)")
    axes[0].legend(fontsize=7, loc="upper left")
    weights.axvspan(124.5, 127.5, **hidden)
    weights.plot(t, 1.0 - meas.alpha[:, 2], "-", color=PALETTE[0], label="weight of the 2nd "
                 "term, 1 − α³")
    weights.plot(t, meas.alpha[:, 2] * (1.0 - meas.alpha[:, 1]), "--", color=PALETTE[1],
                 label="weight of the 3rd term, α³ (1 − α²) / N₃ (N₃ = 1)")
    weights.set(xlabel="frame k", ylabel="weight", xlim=(100, 149), ylim=(-0.03, 1.05),
                title="the weights of the two terms (the same for both settings)")
    weights.legend(fontsize=7, loc="lower left")
    fig10.suptitle("Fig. 10: terms of eq. (13) for the legs")

    fig11 = Figure(figsize=(7.5, 6.0), layout="constrained")
    top, bottom = fig11.subplots(2, 1, sharex=True)
    sl = slice(100, 150)
    body = scene.centres[:, 1, 0]  # the torso's true x: the body's centre line
    top.axvspan(124.5, 127.5, **hidden)
    top.plot(t[sl], scene.centres[sl, 2, 0] - body[sl], "-", color=TRUTH_COLOR, lw=2.0,
             label="truth: leg centre")
    top.plot(t[sl], meas.z[sl, 2, 0] - body[sl], "x", color=FAILURE_COLOR, ms=4,
             label="measured: visible centroid")
    top.plot(t[sl], spec["_skf"].prior[sl, 2, 0] - body[sl], ".-", color=PALETTE[0], lw=1.2,
             label=r"SKF $m_c^{3-}$, $Q_r = 0.01\,Q_c$")
    top.plot(t[sl], old["_skf"].prior[sl, 2, 0] - body[sl], ".-", color=PALETTE[3], lw=0.9,
             label=r"SKF $m_c^{3-}$, $Q_r = Q_c$ (variant)")
    top.plot(t[sl], spec["_base"][sl, 2, 0] - body[sl], ".--", color=PALETTE[1], lw=0.9,
             label="independent KF prediction")
    top.set(ylabel="x − body centre line 20 + 2k (px)",
            title="Fig. 11: the legs' predicted centre against the truth")
    top.legend(fontsize=7, loc="lower left", ncol=2)
    a, b = WINDOW
    k = np.arange(a, b + 1)
    bottom.axvspan(124.5, 127.5, **hidden)
    for run_, name, color in ((spec, "SKF, Q_r = 0.01·Q_c", PALETTE[0]),
                              (old, "SKF, Q_r = Q_c (variant)", PALETTE[3]),
                              (cv, "SKF, CV model (variant)", PALETTE[2])):
        bottom.plot(k, run_["_err"], "-", color=color, label=name)
    bottom.plot(k, spec["_base_err"], "--", color=PALETTE[1], label="independent KFs")
    bottom.axhline(TARGET_PX, color="black", ls=":", lw=1.0, label="[R] target 7 px")
    bottom.set(xlabel="frame k", ylabel=r"$\|m_c^{3-} - $ truth$\|$ (px)", ylim=(0, None))
    bottom.legend(fontsize=7, loc="upper left", ncol=2)

    fig_s = Figure(figsize=(6.5, 3.4), layout="constrained")
    ax = fig_s.subplots()
    ratios = [float(r) for r in sweep]
    x = np.arange(len(ratios))
    mx = [sweep[r]["skf_max_err"] for r in sweep]
    base = [sweep[r]["baseline_max_err"] for r in sweep]
    colors = [PALETTE[2] if sweep[r]["target_met"] else FAILURE_COLOR for r in sweep]
    ax.bar(x, mx, color=colors, edgecolor="black", lw=0.6)
    ax.axhline(TARGET_PX, color="black", ls=":", label="[R] target 7 px")
    ax.plot(x, base, "s--", color=PALETTE[1], label="independent KFs")
    for xi, v in zip(x, mx, strict=True):
        ax.annotate(f"{v:.1f}", (xi, v), xytext=(0, 2), textcoords="offset points",
                    ha="center", fontsize=7)
    ax.set_xticks(x, [f"{r:g}" + (" (default)" if r == 0.01 else "") for r in ratios],
                  rotation=20)
    ax.set(xlabel="Q_r / Q_c", ylabel="max leg error, k ∈ [115, 140] (px)",
           title="Sensitivity to the relation process noise")
    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(facecolor=PALETTE[2], edgecolor="black", label="target met"),
                Patch(facecolor=FAILURE_COLOR, edgecolor="black", label="target not met")]
    ax.legend(handles=handles, fontsize=7)
    return {"fig9_alpha": fig9, "fig10_terms": fig10, "fig11_legs": fig11,
            "q_rel_sweep": fig_s}
