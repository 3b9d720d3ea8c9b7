"""X5's measurements of one tracked rendering: vehicles followed, waiting vehicles, extra tracks.

The scene's :data:`CATEGORIES`, the paper's figures (:data:`PAPER`), and the counts by movement
from a track log or from the ground truth.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments._video import SceneRun, summarise
from mvtrack.types import TrackState

CATEGORIES = ("straight", "left", "right", "waiting")
MOVING = CATEGORIES[:3]
PAPER = {
    "vehicles": {"straight": 11, "left": 6, "right": 1, "waiting": 2},
    "tracked": "all straight and turning vehicles, by both predictors",
    "extra_tracks": "more trajectories than vehicles (camera motion, colour-split segmentation)",
    "real_time": "30 fps on a 200 MHz Pentium Pro",
}


#: frames the waiting vehicles stand at the stop line (SPEC X5)
WAIT = (60, 300)


MIN_ASSOC = 5
COVER = 0.8


def _waiting(run: SceneRun) -> list[dict[str, Any]]:
    """Per waiting vehicle: whether one track follows it through ≥ 80 % of its wait (it keeps
    its ID), the share that track holds, and how many tracks were on it during the wait."""
    out = []
    for v in run.scene.ids_of("waiting").tolist():
        ids = run.match.followers(v, WAIT)[0]
        share = run.match.followed_share(v, WAIT)[1]
        out.append({
            "vehicle": v,
            "tracks_during_wait": int(ids.size),
            "wait_share_of_best_track": round(share, 3),
            "keeps_id": bool(share >= COVER),
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


def _twins(run: SceneRun) -> dict[str, float]:
    """Vehicles followed by two tracks at once (a split blob, both parts tracked).

    ``frames_share``: the share of the moving vehicles' visible frames with two or more
    tracks on the vehicle; ``separation_px``: the median distance between the two tracks
    nearest the vehicle in those frames (0 when they output the same position).
    """
    m, scene = run.match, run.scene
    cols = run.log.columns()
    order = np.argsort(cols["frame"], kind="stable")
    fr = cols["frame"][order]
    keep = cols["track_id"][order] > 0
    xy = cols["filtered_xy"][order]
    n_twin, n_all, seps = 0, 0, []
    # two tracks on one vehicle: how far apart their outputs are (offline, per vehicle-frame)
    for v in np.concatenate([scene.ids_of(c) for c in MOVING]).tolist():  # ~20 vehicles
        sel = np.flatnonzero(m.gt_id == v)
        for g in sel.tolist():
            f = m.gt_frame[g]
            a, b = np.searchsorted(fr, f), np.searchsorted(fr, f, side="right")
            d = np.linalg.norm(xy[a:b][keep[a:b]] - m.gt_xy[g], axis=1)
            near = np.sort(d[d <= m.gt_radius[g]])
            n_all += 1
            if near.size >= 2:
                n_twin += 1
                two = xy[a:b][keep[a:b]][np.argsort(d)[:2]]
                seps.append(float(np.linalg.norm(two[0] - two[1])))
    return {"frames_share": n_twin / max(n_all, 1),
            "separation_px": float(np.median(seps)) if seps else float("nan"),
            "exact_ties_share": float(np.mean(np.asarray(seps) == 0.0)) if seps else 0.0}


def _score(run: SceneRun) -> dict[str, float]:
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))
    m = evaluate(MotTable.from_rows(run.scene.gt_mot()), pred, with_hota=False)
    return {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW", "FP", "FN")}


#: the categories the counting module reports (X5's four, u-turns and incomplete tracks)
COUNTED = (*CATEGORIES, "u-turn", "incomplete")


def _counts(run: SceneRun) -> dict[str, int]:
    """X5's categories recovered by the counting module from the run's tracks."""
    from mvtrack.analytics import TrackPoints, analyse, settings_from_dict
    from mvtrack.analytics.accuracy import x5_categories, x5_settings

    res = analyse(TrackPoints.from_log(run.log), settings_from_dict(x5_settings()),
                  run.scene.fps, run.scene.n_frames)
    return x5_categories(res)


def count_truth(scene: Any) -> dict[str, int]:
    """The same, from the scene's true tracks (what a perfect tracker gives)."""
    from mvtrack.analytics import analyse, settings_from_dict
    from mvtrack.analytics.accuracy import scene_points, x5_categories, x5_settings

    res = analyse(scene_points(scene), settings_from_dict(x5_settings()), scene.fps,
                  scene.n_frames)
    return x5_categories(res)


def measure_run(run: SceneRun) -> dict[str, Any]:
    scene = run.scene
    summ = summarise(run, MIN_ASSOC)
    followed, paired = {}, {}
    for c in CATEGORIES:
        ids = scene.ids_of(c).tolist()
        followed[c] = sum(1 for v in ids if run.match.followed_share(v)[1] >= COVER)
        paired[c] = sum(1 for v in ids if summ["coverage"][v]["coverage"] >= COVER)
    return {
        "tracks": summ["tracks"],
        "spurious": summ["spurious"],
        "followed": followed,
        "paired": paired,
        "totals": {c: int(scene.ids_of(c).size) for c in CATEGORIES},
        "waiting": _waiting(run),
        "spurious_causes": _spurious_causes(run),
        "twins": _twins(run),
        "score": _score(run),
        "ms_per_frame": 1000.0 / max(run.result.processing_speed, 1e-9),
        "stopped_rows": int((run.log.columns()["state"] == int(TrackState.STOPPED)).sum()),
        "counts": _counts(run),
    }
