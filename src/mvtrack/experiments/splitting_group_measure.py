"""X8's measurements of one tracked rendering: the group's track and on whom it continues.

The group's track is the one on the merged blob in the :data:`BEFORE` frames before the split;
once P1 walks alone (first isolated: visible, ≥ :data:`ISOLATION_PX` from P2 and P3) it
continues on P1, P2, P3 or ends (:data:`OUTCOMES`); P1's own track, its latency and offsets.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.experiments._video import SceneRun

DISTANCES = ("uncoupled", "coupled", "mahalanobis")
LABELS = {"uncoupled": "eq. (9)", "coupled": "eq. (10), corrected (SPEC §2.3)",
          "mahalanobis": "Mahalanobis", "default": "modern default (variant)"}


HOLD = 0.9
ISOLATION_PX = 12.0
#: frames before the split over which the group's track is identified, and after P1's first
#: isolated frame over which it is followed
BEFORE, AFTER = 15, 15


OUTCOMES = ("P1", "P2", "P3", "ends")


#: the [R] geometry's variant: the car hides the lower half of everyone over it (no depth order)
NO_DEPTH = "car without depth order"


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


def score_run(run: SceneRun) -> dict[str, float]:
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.mot import MotTable

    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))
    m = evaluate(MotTable.from_rows(run.scene.gt_mot()), pred, with_hota=False)
    return {k: float(m[k]) for k in ("MOTA", "IDF1", "IDSW")}
