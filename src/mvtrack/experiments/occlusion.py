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
    and 3rd terms of (13) (T, K), search boxes (T, 4)."""

    prior: FloatArray
    post: FloatArray
    own: FloatArray
    neighbours: FloatArray
    search: FloatArray


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
    post[0] = prior[0] = meas.z[0]
    last_wh = meas.wh[0].copy()
    for t in range(1, T):
        state = predict(params, state)
        prior[t] = state.xc[0, :, :2]
        search[t] = search_region(state.xc[:, :, :2], last_wh[None])[0]
        state, terms = update(params, graph, state, meas.z[t : t + 1], meas.alpha[t : t + 1])
        post[t] = state.xc[0, :, :2]
        own[t] = np.linalg.norm(terms.own[0, :, :2], axis=-1)
        nb[t] = np.linalg.norm(terms.neighbours[0, :, :2], axis=-1)
        seen = np.all(np.isfinite(meas.wh[t]), axis=-1)
        last_wh = np.where(seen[:, None], meas.wh[t], last_wh)
    return SKFRun(prior, post, own, nb, search)


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


#: filter settings compared in X9: the SPEC §3.3 defaults first (the headline figures)
VARIANTS: dict[str, dict] = {
    "spec-default (CA, q=0.05)": {},
    "cv (E3.6 option)": {"model": "cv"},
    "ca, stiff relations (q_rel=0.001, relation_noise=occlusion)": {
        "q_rel": 0.001,
        "relation_noise": "occlusion",
    },
}


def _evaluate(scene: OcclusionScene, meas: PartMeasurements, kw: dict) -> dict:
    params = SKFParams(**kw)
    skf = run_skf(meas, params)
    base = run_independent(meas, SKFParams(model=params.model))
    smax, srms, _ = _errors(skf.prior, scene.centres)
    bmax, brms, _ = _errors(base, scene.centres)
    lost = ~_contains(skf.search, scene.boxes[:, 2])
    return {
        "skf_max_err": smax,
        "skf_rms_err": srms,
        "baseline_max_err": bmax,
        "baseline_rms_err": brms,
        "frames_lost": np.flatnonzero(lost).tolist(),
        "_skf": skf,
        "_base": base,
    }


def run(*, runs: int | None = None, seed: int = 0) -> Report:
    """Run X9 ``runs`` times (sensor-noise seeds ``seed``, ``seed+1``, …; default 1).

    Every filter variant of :data:`VARIANTS` is run on the label measurements, and the SPEC
    default also on the segmentation measurements; figures are means over the runs.
    """
    n_runs = 1 if runs is None else int(runs)
    if n_runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    per_run = []
    first: dict = {}
    for r in range(n_runs):
        scene = render_occlusion_scene(seed=seed + r)
        meas = measurements_from_labels(scene)
        res = {name: _evaluate(scene, meas, kw) for name, kw in VARIANTS.items()}
        seg_meas, n_parts = measurements_from_segmentation(scene)
        res["segmentation, spec-default"] = _evaluate(scene, seg_meas, {})
        res["segmentation, cv"] = _evaluate(scene, seg_meas, {"model": "cv"})
        res["_parts"] = n_parts
        res["_alpha_peak"] = _peak(meas.alpha[:, 2])
        per_run.append(res)
        if r == 0:
            first = {"scene": scene, "meas": meas, "res": res}

    keys = ("skf_max_err", "skf_rms_err", "baseline_max_err", "baseline_rms_err")
    variants = {}
    for name in [*VARIANTS, "segmentation, spec-default", "segmentation, cv"]:
        v = {k: float(np.mean([res[name][k] for res in per_run])) for k in keys}
        v["part3_never_lost"] = all(not res[name]["frames_lost"] for res in per_run)
        v["target_met"] = bool(
            v["skf_max_err"] < 7.0
            and v["skf_max_err"] < v["baseline_max_err"]
            and v["part3_never_lost"]
        )
        variants[name] = v
    head = variants["spec-default (CA, q=0.05)"]
    peak, plateau = first["res"]["_alpha_peak"]
    figures = {
        "runs": n_runs,
        "seed": seed,
        "window": list(WINDOW),
        **{k: head[k] for k in keys},
        "alpha_peak_frame": peak,
        "alpha_peak_frames": plateau,
        "part3_never_lost": head["part3_never_lost"],
        "target_met": head["target_met"],
        "segmentation_parts_found": int(min(res["_parts"] for res in per_run)),
        "variants": variants,
        "paper": {
            "alpha_peak_frame": 126,
            "part3_never_lost": True,
            "skf_max_err": None,
            "note": "paper 3 gives plots only (Figs. 9-11), no error figures; [R] target: "
            "SKF max error < 7 px and below the baseline",
        },
    }
    rows = [
        ["α³ peak frame", 126, f"{peak:g} (plateau {plateau[0]}–{plateau[-1]})"],
        ["parts found by segmentation (frame 0)", 3, figures["segmentation_parts_found"]],
    ]
    for name, v in variants.items():
        rows.append(
            [
                f"{name}: SKF max / RMS (px); independent KFs max / RMS (px); never lost",
                "< 7 (target); yes",
                f"{v['skf_max_err']:.3g} / {v['skf_rms_err']:.3g}; "
                f"{v['baseline_max_err']:.3g} / {v['baseline_rms_err']:.3g}; "
                f"{'yes' if v['part3_never_lost'] else 'no'}",
            ]
        )
    res0 = first["res"]
    plots = _plots(
        first["scene"],
        first["meas"],
        res0["spec-default (CA, q=0.05)"]["_skf"],
        res0["spec-default (CA, q=0.05)"]["_base"],
        res0["cv (E3.6 option)"]["_skf"],
    )
    return Report(
        name="occlusion",
        title="X9 — structured KF through partial occlusion (paper 3, Figs. 9–11)",
        figures=figures,
        columns=["quantity", "paper", "ours"],
        rows=rows,
        notes=_notes(n_runs, figures),
        plots=plots,
    )


def _notes(n_runs: int, fig: dict) -> str:
    met = "met" if fig["target_met"] else "NOT met"
    return (
        f"Scene of SPEC X9 (320×240, 150 frames, legs fully hidden at t = 125–127), {n_runs} "
        "noise seed(s); errors are those of the predicted leg centre m_c^{3−}(k) against the "
        "true centre over k ∈ [115, 140] (mean over seeds). The baseline is three independent "
        "KFs of the same model and noise on the visible centroids, coasting when a part has "
        "< 5 visible pixels.\n\n"
        f"With the SPEC §3.3 defaults (6-D CA, Q = 0.05·diag(0,0,0,0,1,1) for cells and "
        f"relations) the [R] target is **{met}**: the legs swing ±2 px about the torso, the CA "
        "relation filter learns that swing as velocity and acceleration, and while α³ is high "
        "(from frame 118) eq. (15) feeds the relation mostly with the legs' own prediction, so "
        "the relation — and with it the leg estimate, which follows torso + relation — "
        "extrapolates the swing for ~17 frames. The 4-D CV option (E3.6), or CA with stiff "
        "relations (q_rel = 0.001, relation noise scaled by 1/((1−α^i)(1−α^j)), options that "
        "are not in paper 3), keep the learned offset and meet the target; see the variants "
        "rows. α³ is 1 on every frame where the legs have no visible pixel and on the first "
        "frame after (no previous features, E3.8), so its maximum is a plateau whose centre is "
        "reported. Parts by segmentation (hue K-means tree inside the SKF search box, matched by "
        "least |ΔF|) give the same measurements as the renderer's labels on this scene."
    )


def _plots(
    scene: OcclusionScene,
    meas: PartMeasurements,
    skf: SKFRun,
    base: FloatArray,
    skf_cv: SKFRun,
) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(meas.z.shape[0])
    fig9, ax = plt.subplots(figsize=(6, 3))
    ax.plot(t, meas.alpha[:, 2], "k-")
    ax.set(xlabel="frame k", ylabel="α³(k)", title="Occlusion degree of the legs (Fig. 9)")
    ax.axvspan(125, 127, color="0.85")
    fig10, axes = plt.subplots(1, 2, figsize=(10, 3), sharey=True)
    for ax, run_, name in ((axes[0], skf, "CA, SPEC default"), (axes[1], skf_cv, "CV option")):
        ax.plot(t, run_.own[:, 2], "k-", label="2nd term of (13): own measurement")
        ax.plot(t, run_.neighbours[:, 2], "k--", label="3rd term of (13): neighbours")
        ax.set(xlabel="frame k", title=f"Terms of eq. (13), j = 3 ({name})")
        ax.set_xlim(100, 149)
        ax.axvspan(125, 127, color="0.85")
    axes[0].set_ylabel("norm (px)")
    axes[0].legend(fontsize=7)
    fig11, ax = plt.subplots(figsize=(6, 3.5))
    sl = slice(100, 150)
    ax.plot(t[sl], scene.centres[sl, 2, 0], "k-", label="true leg centre x")
    ax.plot(t[sl], skf.prior[sl, 2, 0], "b.-", label="SKF (CA, SPEC default) m_c^{3−}")
    ax.plot(t[sl], skf_cv.prior[sl, 2, 0], "c.-", label="SKF (CV option) m_c^{3−}")
    ax.plot(t[sl], base[sl, 2, 0], "r.--", label="independent CA KF prediction")
    ax.plot(t[sl], meas.z[sl, 2, 0], "gx", label="visible centroid")
    ax.axvspan(125, 127, color="0.85")
    ax.set(xlabel="frame k", ylabel="x (px)", title="Leg trajectory (Fig. 11)")
    ax.legend(fontsize=7)
    return {"fig9_alpha": fig9, "fig10_terms": fig10, "fig11_legs": fig11}
