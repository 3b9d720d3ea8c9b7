"""X9: tracking a walker through partial occlusion with the structured KF (paper 3, Figs. 9–11).

The scene of :mod:`mvtrack.sim.occlusion` (three-part walker, legs behind a desk, fully hidden
at t = 125–127) is measured in two ways:

- ``labels``: each part's measurement is the centroid of its visible pixels, taken from the
  renderer's label image; α from eq. (16) with the SPEC §3.3 features between consecutive
  frames (α = 1 when a part has < 5 visible pixels now or had none in the previous frame);
- ``segmentation``: the same, but the parts come from :func:`mvtrack.detection.parts.segment_parts`
  inside the SKF's search region and are matched by :func:`mvtrack.detection.parts.match_parts`.

The SKF (SPEC §3.3 defaults) is compared with three independent CA Kalman filters with the same
noise that use the visible centroid and coast when a part is missing. Errors are those of the
predicted leg centre m_c^{3−}(k) against the true (unoccluded) centre over k ∈ [115, 140].
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.parts import (
    DetectionZone,
    PartFeatures,
    bgr_to_hsi,
    feature_distance,
    match_parts,
    moving_box,
    occlusion_degree,
    region_features,
    segment_parts,
)
from mvtrack.experiments.report import Report
from mvtrack.filters import kalman
from mvtrack.filters.structured import (
    PartGraph,
    SKFParams,
    init,
    predict,
    search_region,
    update,
)
from mvtrack.sim.occlusion import OcclusionScene, render_occlusion_scene

FloatArray = NDArray[np.float64]

#: frames over which the errors are measured (SPEC X9)
WINDOW = (115, 140)
#: fewer visible pixels than this means "no match" (SPEC §3.3)
MIN_PX = 5


@dataclass
class PartMeasurements:
    """Per-frame part measurements of one object: z (T, K, 2) NaN when missing, α (T, K),
    last box sizes wh (T, K, 2)."""

    z: FloatArray
    alpha: FloatArray
    wh: FloatArray


def _features(frame: NDArray[np.uint8], labels: NDArray[np.integer], k: int) -> PartFeatures:
    hue, sat, inten = bgr_to_hsi(frame)
    return region_features(labels, k, hue, sat, inten)


def measurements_from_labels(scene: OcclusionScene) -> PartMeasurements:
    """Visible centroids, α of eq. (16) between consecutive frames and box sizes."""
    T, K = scene.labels.shape[0], 3
    z = np.full((T, K, 2), np.nan)
    alpha = np.ones((T, K))
    wh = np.full((T, K, 2), np.nan)
    prev: PartFeatures | None = None
    for t in range(T):  # per frame; the features of all parts are computed at once
        f = _features(scene.frames[t], scene.labels[t], K)
        seen = f.area >= MIN_PX
        z[t] = np.where(seen[:, None], f.centroid, np.nan)
        wh[t] = np.where(seen[:, None], f.wh, np.nan)
        if prev is not None:
            dF = np.diag(feature_distance(prev, f))
            ok = seen & (prev.area >= MIN_PX)
            alpha[t] = np.where(ok, occlusion_degree(dF), 1.0)  # eq. (16), no match -> 1
        else:
            alpha[t] = np.where(seen, 0.0, 1.0)
        prev = f
    return PartMeasurements(z, alpha, wh)


@dataclass
class SKFRun:
    """Trajectories of one filter run: prior (T, K, 2), posterior (T, K, 2), norms of the 2nd
    and 3rd terms of (13) (T, K), search boxes (T, 4), relation priors (T, E, n): offset,
    its velocity (and acceleration)."""

    prior: FloatArray
    post: FloatArray
    own: FloatArray
    neighbours: FloatArray
    search: FloatArray
    relation: FloatArray


def run_skf(meas: PartMeasurements, params: SKFParams | None = None) -> SKFRun:
    """The SKF over a whole sequence (one object, chain head–torso–legs)."""
    params = params or SKFParams()
    graph = PartGraph.chain(3)
    T, K = meas.z.shape[:2]
    prior = np.full((T, K, 2), np.nan)
    post = np.full((T, K, 2), np.nan)
    own = np.zeros((T, K))
    nb = np.zeros((T, K))
    search = np.full((T, 4), np.nan)
    state = init(params, graph, meas.z[:1])
    relation = np.full((T, graph.n_edges, params.n), np.nan)
    relation[0] = state.xr[0]
    post[0] = prior[0] = meas.z[0]
    last_wh = meas.wh[0].copy()
    for t in range(1, T):
        state = predict(params, state)
        prior[t] = state.xc[0, :, :2]
        relation[t] = state.xr[0]
        search[t] = search_region(state.xc[:, :, :2], last_wh[None])[0]
        state, terms = update(params, graph, state, meas.z[t : t + 1], meas.alpha[t : t + 1])
        post[t] = state.xc[0, :, :2]
        own[t] = np.linalg.norm(terms.own[0, :, :2], axis=-1)
        nb[t] = np.linalg.norm(terms.neighbours[0, :, :2], axis=-1)
        seen = np.all(np.isfinite(meas.wh[t]), axis=-1)
        last_wh = np.where(seen[:, None], meas.wh[t], last_wh)
    return SKFRun(prior, post, own, nb, search, relation)


def run_independent(meas: PartMeasurements, params: SKFParams | None = None) -> FloatArray:
    """Baseline: independent KFs per part on the visible centroid, coasting when missing.

    Uses the plain batched filter of :mod:`mvtrack.filters.kalman` with the SKF's model.

    Returns the prior positions (T, K, 2).
    """
    params = params or SKFParams()
    T, K = meas.z.shape[:2]
    x = np.zeros((K, params.n))
    x[:, :2] = meas.z[0]
    P = np.broadcast_to(params.P0(params.r_cell), (K, params.n, params.n)).copy()
    prior = np.full((T, K, 2), np.nan)
    prior[0] = meas.z[0]
    for t in range(1, T):
        x, P = kalman.predict(x, P, params.F, params.Q)
        prior[t] = x[:, :2]
        x, P = kalman.update(x, P, meas.z[t], params.H, params.R_cell)  # NaN rows coast
    return prior


def measurements_from_segmentation(
    scene: OcclusionScene, params: SKFParams | None = None
) -> tuple[PartMeasurements, int]:
    """Parts found by hue segmentation inside the SKF's search region, matched frame to frame.

    The walker is picked up in the door zone (the detection zone) as the MER of the moving
    region of frames 0 and 1 (:func:`~mvtrack.detection.parts.moving_box`), and frame 0 is
    segmented inside it; afterwards the segmented
    regions inside the predicted search box are matched to the previous parts by least |ΔF|.
    The filter runs alongside (its prediction gives the search box).

    Returns
    -------
    meas : PartMeasurements
    n_initial_parts : int
        How many parts the first segmentation found.
    """
    params = params or SKFParams()
    T = scene.frames.shape[0]
    K = 3
    z = np.full((T, K, 2), np.nan)
    alpha = np.ones((T, K))
    wh = np.full((T, K, 2), np.nan)
    H, W = scene.labels.shape[1:]
    # pick-up: the moving region (difference of frames 0 and 1) inside the door zone
    box = moving_box(scene.frames[0], scene.frames[1], DetectionZone(*scene.door))
    if box is None:
        raise ValueError("no moving object in the detection zone at frame 1")
    x0, y0, x1, y1 = (int(v) for v in box)
    mask = np.zeros((H, W), dtype=bool)
    mask[y0:y1, x0:x1] = True
    hue, sat, inten = bgr_to_hsi(scene.frames[0])
    labels, hues = segment_parts(hue, sat, mask)
    f = region_features(labels, len(hues), hue, sat, inten)
    n0 = len(hues)
    if n0 < K:
        raise ValueError(f"segmentation of the first frame found {n0} parts, need {K}")
    prev = _take(f, np.arange(K))
    z[0], wh[0], alpha[0] = prev.centroid, prev.wh, 0.0
    graph = PartGraph.chain(K)
    state = init(params, graph, z[:1])
    last_wh = wh[0].copy()
    for t in range(1, T):
        state = predict(params, state)
        box = search_region(state.xc[:, :, :2], last_wh[None])[0]
        mask[:] = False
        bx0, by0 = max(int(np.floor(box[0])), 0), max(int(np.floor(box[1])), 0)
        bx1, by1 = min(int(np.ceil(box[2])), W), min(int(np.ceil(box[3])), H)
        mask[by0:by1, bx0:bx1] = True
        hue, sat, inten = bgr_to_hsi(scene.frames[t])
        labels, hues = segment_parts(hue, sat, mask)
        cur = region_features(labels, len(hues), hue, sat, inten)
        idx, a = match_parts(prev, cur, min_px=MIN_PX)
        got = idx >= 0
        sel = np.where(got, idx, 0)
        if len(hues):
            z[t] = np.where(got[:, None], cur.centroid[sel], np.nan)
            wh[t] = np.where(got[:, None], cur.wh[sel], np.nan)
        # α = 1 also when the part was missing in the previous frame (F(k−1) undefined, E3.8)
        alpha[t] = np.where(got & np.isfinite(z[t - 1, :, 0]), a, 1.0)
        state, _ = update(params, graph, state, z[t : t + 1], alpha[t : t + 1])
        if len(hues):
            prev = _replace_rows(prev, cur, idx)  # (a no-op when nothing was found)
        last_wh = np.where(got[:, None], wh[t], last_wh)
    return PartMeasurements(z, alpha, wh), n0


def _take(f: PartFeatures, rows: NDArray[np.intp]) -> PartFeatures:
    return PartFeatures(f.area[rows], f.centroid[rows], f.wh[rows], f.hue[rows], f.sigma_i[rows])


def _replace_rows(prev: PartFeatures, cur: PartFeatures, idx: NDArray[np.intp]) -> PartFeatures:
    """Matched parts take their current features; unmatched ones keep their last features."""
    got = idx >= 0
    sel = np.where(got, idx, 0)
    return PartFeatures(
        area=np.where(got, cur.area[sel], prev.area),
        centroid=np.where(got[:, None], cur.centroid[sel], prev.centroid),
        wh=np.where(got[:, None], cur.wh[sel], prev.wh),
        hue=np.where(got, cur.hue[sel], prev.hue),
        sigma_i=np.where(got, cur.sigma_i[sel], prev.sigma_i),
    )


def _errors(prior: FloatArray, truth: FloatArray) -> tuple[float, float, FloatArray]:
    a, b = WINDOW
    e = np.linalg.norm(prior[a : b + 1, 2] - truth[a : b + 1, 2], axis=-1)
    return float(e.max()), float(np.sqrt(np.mean(e**2))), e


def _contains(search: FloatArray, boxes: FloatArray) -> FloatArray:
    """Whether each search box (T, 4) contains the full legs box (T, 4); frame 0 counts."""
    inside = (
        (search[:, 0] <= boxes[:, 0])
        & (search[:, 1] <= boxes[:, 1])
        & (search[:, 2] >= boxes[:, 2])
        & (search[:, 3] >= boxes[:, 3])
    )
    inside[0] = True
    return inside


def _peak(alpha3: FloatArray) -> tuple[float, list[int]]:
    top = np.flatnonzero(alpha3 >= alpha3.max() - 1e-12)
    # the maximum may be a plateau (α = 1 on every frame with no match): report its centre
    return float(np.mean(top)), top.tolist()


#: the SKF's default (SPEC §3.3 with E3.12, Q_r = 0.01·Q_c): the headline figures
HEADLINE = "spec"
#: settings run besides the specification's: name -> (SKFParams keywords, reason)
VARIANTS: dict[str, tuple[dict[str, Any], str]] = {
    "Q_r = Q_c": (
        {"q_rel": 0.05},
        "the previous default (the first reconstruction, one Q for cells and relations); "
        "E3.12 replaced it",
    ),
    "CV model": (
        {"model": "cv"},
        "the 4-D constant-velocity reading of eqs. (4) and (6) (E3.6 option)",
    ),
    "1/Σ(1 − α^i)": (
        {"normalise": "weights"},
        "the specification's other normalisation of eq. (13) (SPEC §3.3 option, E3.2)",
    ),
    "inferred from (15)": (
        {"inferred": "measurement"},
        "the literal eq. (7) fed with the relation measurement of (15) (SPEC §3.3 option, "
        "E3.4)",
    ),
    "coasting relation keeps its velocity": (
        {"relation_damping": 1.0},
        "the specification read literally: a relation with an unmatched end has its terms "
        "dropped and coasts by Φ alone; the default's damping of its derivatives (0.8 a "
        "frame) is ours",
    ),
    "coasting relation holds its offset": (
        {"relation_damping": 0.0},
        "our alternative to the 0.8 damping, not in paper 3: a relation with an unmatched "
        "end keeps its last offset (its derivatives set to zero)",
    ),
    "cells before relations": (
        {"order": "cells-first"},
        "not the specification's order (SPEC §3.1 step 5 updates the relations first, (15) "
        "with the cells' priors): eq. (13) first, then (15) with the cells' posteriors",
    ),
    "stiff relations, occlusion-scaled R_r": (
        {"q_rel": 0.001, "relation_noise": "occlusion"},
        "our option, not in paper 3: R_r / ((1 − α^i)(1 − α^j)) keeps an occluded part's own "
        "prediction out of the relation",
    ),
}
#: the part measurements from hue segmentation instead of the renderer's labels
SEGMENTATION = "segmentation"
SEGMENTATION_REASON = (
    "parts found by hue K-means inside the SKF's search box and matched by least |ΔF| "
    "(the full paper-3 front end) instead of the renderer's label image"
)
#: Q_r / Q_c ratios of the sensitivity sweep (the default, 0.01, among them)
RATIOS = (1.0, 0.1, 0.03, 0.01, 0.003, 0.001, 0.0)
#: the [R] pass mark of SPEC X9 (px)
TARGET_PX = 7.0


def _evaluate(scene: OcclusionScene, meas: PartMeasurements, kw: dict[str, Any]) -> dict:
    params = SKFParams(**kw)
    skf = run_skf(meas, params)
    base = run_independent(meas, SKFParams(model=params.model))
    smax, srms, err = _errors(skf.prior, scene.centres)
    bmax, brms, berr = _errors(base, scene.centres)
    lost = ~_contains(skf.search, scene.boxes[:, 2])
    return {
        "skf_max_err": smax,
        "skf_rms_err": srms,
        "skf_max_err_frame": int(WINDOW[0] + np.argmax(err)),
        "baseline_max_err": bmax,
        "baseline_rms_err": brms,
        "frames_lost": np.flatnonzero(lost).tolist(),
        "_skf": skf,
        "_base": base,
        "_err": err,
        "_base_err": berr,
    }


def _summary(results: list[dict]) -> dict[str, Any]:
    """Means over the seeds and the [R] pass of SPEC X9 for one setting."""
    keys = ("skf_max_err", "skf_rms_err", "baseline_max_err", "baseline_rms_err")
    v: dict[str, Any] = {k: float(np.mean([r[k] for r in results])) for k in keys}
    v["skf_max_err_worst_seed"] = float(max(r["skf_max_err"] for r in results))
    v["skf_max_err_frame"] = int(np.median([r["skf_max_err_frame"] for r in results]))
    v["part3_never_lost"] = all(not r["frames_lost"] for r in results)
    v["below_baseline"] = bool(v["skf_max_err"] < v["baseline_max_err"])
    v["below_target"] = bool(v["skf_max_err"] < TARGET_PX)
    v["target_met"] = bool(v["below_target"] and v["below_baseline"] and v["part3_never_lost"])
    return v


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Run X9 ``runs`` times (sensor-noise seeds ``seed``, ``seed+1``, …; default 1).

    The SKF's default (SPEC §3.3 with E3.12) gives the headline figures; every setting of
    :data:`VARIANTS`, the segmentation front end and the Q_r / Q_c sweep :data:`RATIOS` are
    run on the same measurements. Figures are means over the runs.
    """
    n_runs = 1 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    names = [HEADLINE, *VARIANTS, SEGMENTATION]
    per: dict[str, list[dict]] = {n: [] for n in names}
    sweep: dict[float, list[dict]] = {r: [] for r in RATIOS}
    first: dict[str, Any] = {}
    parts, peaks = [], []
    q = SKFParams().q
    for r in range(n_runs):
        scene = render_occlusion_scene(seed=seed + r)
        meas = measurements_from_labels(scene)
        per[HEADLINE].append(_evaluate(scene, meas, {}))
        for name, (kw, _) in VARIANTS.items():
            per[name].append(_evaluate(scene, meas, kw))
        seg_meas, n_parts = measurements_from_segmentation(scene)
        per[SEGMENTATION].append(_evaluate(scene, seg_meas, {}))
        for ratio in RATIOS:
            sweep[ratio].append(_evaluate(scene, meas, {"q_rel": ratio * q}))
        parts.append(n_parts)
        peaks.append(_peak(meas.alpha[:, 2]))
        if r == 0:
            first = {"scene": scene, "meas": meas}

    summary = {n: _summary(per[n]) for n in names}
    for name, (kw, why) in VARIANTS.items():
        summary[name] |= {"settings": kw, "reason": why}
    summary[SEGMENTATION] |= {"settings": {}, "reason": SEGMENTATION_REASON}
    head = summary[HEADLINE]
    peak, plateau = peaks[0]
    terms = per[HEADLINE][0]["_skf"]
    clear, hid = slice(100, 118), slice(118, 135)  # legs unoccluded / partly or fully hidden
    drift = per[HEADLINE][0]["_skf"].relation[125, 1, 2]  # legs − torso, velocity x
    figures: dict[str, Any] = {
        "runs": n_runs,
        "seed": seed,
        "window": list(WINDOW),
        "settings": {"q": q, "q_rel": 0.01 * q, "model": "ca", "r_cell": 4.0, "r_rel": 8.0},
        **{k: head[k] for k in ("skf_max_err", "skf_rms_err", "baseline_max_err",
                                 "baseline_rms_err", "skf_max_err_frame",
                                 "skf_max_err_worst_seed")},
        "part3_never_lost": head["part3_never_lost"],
        "below_baseline": head["below_baseline"],
        "below_target": head["below_target"],
        "target_met": head["target_met"],
        "target_px": TARGET_PX,
        "alpha_peak_frame": peak,
        "alpha_peak_frames": plateau,
        "terms_mean_px": {
            "second_unoccluded": float(terms.own[clear, 2].mean()),
            "second_occluded": float(terms.own[hid, 2].mean()),
            "third_unoccluded": float(terms.neighbours[clear, 2].mean()),
            "third_occluded": float(terms.neighbours[hid, 2].mean()),
        },
        "third_term_rises_as_second_falls": bool(
            terms.own[hid, 2].mean() < terms.own[clear, 2].mean()
            and terms.neighbours[hid, 2].mean() > terms.neighbours[clear, 2].mean()),
        "relation_velocity_at_full_occlusion": float(drift),
        "segmentation_parts_found": int(min(parts)),
        "variants": {n: summary[n] for n in names[1:]},
        "q_rel_sweep": {
            f"{ratio:g}": _summary(sweep[ratio]) | {"q_rel": ratio * q} for ratio in RATIOS
        },
        "paper": {
            "alpha_peak_frame": 126,
            "part3_never_lost": True,
            "third_term_rises_as_second_falls": True,
            "note": "paper 3 gives plots only (Figs. 9-11), no error figures; [R] target: "
            "SKF max error < 7 px and below the baseline, part 3 never lost",
        },
    }
    yes = {True: "yes", False: "**no**"}

    def errs(v: dict[str, Any]) -> str:
        return (f"{v['skf_max_err']:.2f} / {v['skf_rms_err']:.2f} (independent KFs "
                f"{v['baseline_max_err']:.2f} / {v['baseline_rms_err']:.2f})")

    rows: list[list[Any]] = [
        ["α³ peak frame", 126, f"{peak:g} (plateau {plateau[0]}–{plateau[-1]})"],
        ["3rd term of (13) rises as the 2nd falls (mean ‖term‖, frames 118–134 against "
         "100–117)", "yes", yes[figures["third_term_rises_as_second_falls"]] + " ({:.2f} → "
         "{:.2f} and {:.2f} → {:.2f} px)".format(*(figures["terms_mean_px"][k] for k in (
             "second_unoccluded", "second_occluded", "third_unoccluded", "third_occluded")))],
        ["part 3 never lost (search box holds the legs in every frame)", "yes",
         yes[head["part3_never_lost"]]],
        ["leg error max / RMS over k ∈ [115, 140] (px)", "max < 7 [R]", errs(head)],
        ["max error < 7 px", "yes [R]", f"{yes[head['below_target']]} "
         f"({head['skf_max_err']:.2f} px at frame {head['skf_max_err_frame']})"],
        ["max error below the independent KFs'", "yes [R]", yes[head["below_baseline"]]],
        ["parts found by segmentation (frame 0)", 3, figures["segmentation_parts_found"]],
    ]
    for name in names[1:]:
        v = summary[name]
        rows.append([f"variant *{name}*: leg error max / RMS (px); target met", "—",
                     f"{errs(v)}; {yes[v['target_met']]}"])
    variants = {name: why for name, (_, why) in VARIANTS.items()}
    variants[SEGMENTATION] = SEGMENTATION_REASON
    return Report(
        name="occlusion",
        title="X9 — structured KF through partial occlusion (paper 3, Figs. 9–11)",
        figures=figures,
        columns=["quantity", "paper", "ours (SPEC §3.3, Q_r = 0.01·Q_c)"],
        rows=rows,
        notes=_notes(n_runs, figures),
        plots={**_plots(first["scene"], first["meas"], per, figures["q_rel_sweep"]),
               "designs": _designs_plot(figures)},
        variants=variants,
    )


def _designs_plot(fig: dict[str, Any]) -> Any:
    """Maximum leg error of the default and of every variant (bars; grey where the [R]
    target is missed), beside the independent KFs' and the 7 px mark."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from mvtrack.viz.plots import FAILURE_COLOR, PALETTE

    runs = {"SPEC default": fig, **fig["variants"]}
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


def _notes(n_runs: int, fig: dict) -> str:
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
    return f"""
Scene of SPEC X9 (320×240, 150 frames, legs partly hidden at t = 118–134 and fully at
t = 125–127, sensor noise σ = 2 grey levels), {n_runs} noise seed(s) from {fig['seed']};
errors are those of the predicted leg centre m_c^{{3−}}(k) against the true centre over
k ∈ [115, 140] (means over the seeds). The baseline is three independent KFs of the same model
and noise on the visible centroids, coasting when a part has < 5 visible pixels. The SKF runs
the SPEC §3.3 defaults: 6-D CA cells and relations, Q_c = 0.05·diag(0, 0, 0, 0, 1, 1),
Q_r = 0.01·Q_c (E3.12), R_c = 4 px², R_r = 8 px², inferred measurements from the relation
prior, 1/N_j.

The [R] target (maximum error < {TARGET_PX:g} px, below the baseline, part 3 never lost) is
{verdict}: maximum error {fig['skf_max_err']:.2f} px at frame {fig['skf_max_err_frame']}
(worst seed {fig['skf_max_err_worst_seed']:.2f} px) against {fig['baseline_max_err']:.2f} px
for the independent KFs, RMS {fig['skf_rms_err']:.2f} against {fig['baseline_rms_err']:.2f}
px; the search box holds the legs in every frame. E3.12 cuts the previous default's error
(Q_r = Q_c: {old['skf_max_err']:.1f} px) by a factor {old['skf_max_err'] / fig['skf_max_err']:.1f}
and now beats the baseline by {fig['baseline_max_err'] / fig['skf_max_err']:.1f}×. What is left
comes from the relation's velocity: before the occlusion the legs swing from +2 to −2 px about
the torso, the relation filter (even with Q_r = 0.01·Q_c) carries
{fig['relation_velocity_at_full_occlusion']:.2f} px/frame of that swing into the occlusion
(its prior velocity along x at frame 125, when the legs vanish), and while α³ ≈ 1 eq. (15)
measures the relation by the legs' own prediction, so nothing corrects it; the leg estimate (torso +
relation) drifts until the legs come back and α³ falls (largest error at frame
{fig['skf_max_err_frame']}). Smaller ratios meet the mark (sweep:
Q_r / Q_c ∈ {{{", ".join(met)}}} do, see `q_rel_sweep` and the plot); we keep the
specification's 0.01 and do not tune the default to this scene.

**Other designs, same measurements.** The specification's own options and its literal reading
of a relation with an unmatched end: {spec_options}. Two designs outside the specification:
{ours}. We adopt neither as the default: the damping of a coasting relation is not in paper 3
(the default's 0.8 is ours too), and setting it to 0 because it passes on this scene would tune
it to the scene; running (13) before (15) reverses the order of SPEC §3.1 step 5 and replaces
the cell priors of eq. (15) by posteriors.

α³ is 1 on every frame where the legs have no visible pixel and on the first frame after (no
previous features, E3.8), so its maximum is a plateau whose centre is reported. Parts by
segmentation (hue K-means tree inside the SKF search box, matched by least |ΔF|) give the same
measurements as the renderer's labels on this scene (variant *{SEGMENTATION}*).
"""


def _plots(
    scene: OcclusionScene,
    meas: PartMeasurements,
    per: dict[str, list[dict]],
    sweep: dict[str, dict[str, Any]],
) -> dict:
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from mvtrack.viz.plots import FAILURE_COLOR, PALETTE, TRUTH_COLOR

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
