"""The stop-and-go scene (:mod:`mvtrack.sim.queue`) rendered and tracked: does every queued
vehicle keep one ID, and what does the counting module count.

Per seed and tracker (the default as ``mvtrack track`` runs it, and paper 1's tracker with
the CA Kalman filter and with RLS on the SPEC §1.1 [R] blob stage, all with template
matching): the share of each vehicle's visible frames that one track follows (a vehicle keeps
its ID when one track follows it in ≥ 99 % of them), the movement counts against the truth
and the crossings of the stop line (truth: 10 eastbound).

    python benchmarks/bench_queue.py [--seeds 0,1,2] [--trackers default,kalman-ca,rls]

A tracker name may carry front-end options: ``+split`` (``track_split`` with fragments merged,
``track_merge``), ``+nosplit`` (no ``track_split``), ``+ghosts`` (``ghost_every = 5``),
``+hold`` (``hold`` = 60 s), e.g. ``kalman-ca+hold`` or ``default+nosplit``; the default
already has the pipeline's ghost test, hold and split-only ``track_split``.
"""

from __future__ import annotations

import argparse
import json


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--trackers", default="default,kalman-ca,rls")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    from mvtrack.analytics import TrackPoints, analyse, settings_from_dict
    from mvtrack.analytics.accuracy import (
        count_errors,
        line_counts,
        movement_counts,
        truth_movement_counts,
    )
    from mvtrack.experiments._video import (
        PAPER_TEMPLATES,
        default_config,
        pipeline_blob_params,
        track_scene,
    )
    from mvtrack.sim.queue import queue_scene, queue_settings
    from mvtrack.sim.render import render_frames
    from mvtrack.tracking import paper1

    spec_blobs = {"close_size": 0, "min_area": 20.0}
    out: dict[str, dict] = {}
    for seed in (int(s) for s in args.seeds.split(",")):
        sc = queue_scene(seed)
        frames = list(render_frames(sc, seed))
        truth = truth_movement_counts(sc.meta["origin"], sc.meta["destination"])
        queued = [i + 1 for i, c in enumerate(sc.category) if c == "queue"]
        for name in args.trackers.split(","):
            base, *extras = name.split("+")  # "NAME+split+ghosts": front-end options on
            if base == "default":
                cfg, blobs = default_config(sc), pipeline_blob_params(sc.size, sc.fps)
            else:
                cfg, blobs = paper1(base, fps=sc.fps, gate_px=20.0), dict(spec_blobs)
            if "split" in extras:  # blobs split and fragments merged by the predicted boxes
                blobs = {**blobs, "track_split": True, "track_merge": True}
            if "nosplit" in extras:  # the disturbance map's blobs as they are
                blobs = {**blobs, "track_split": False}
            if "ghosts" in extras:  # the disturbance map's ghosts reset to the frame
                blobs = {**blobs, "ghost_every": 5}
            if "hold" in extras:  # tracked pixels kept out of the background for 60 s
                blobs = {**blobs, "hold": round(60 * sc.fps)}
            # paper 1's trackers with paper 1's template matching (SPEC §1.1 step 3)
            run = track_scene(sc, cfg, seed=seed, frames=frames, detector_params=blobs,
                              template_params=None if base == "default" else PAPER_TEMPLATES)
            share = {}
            for v in range(1, sc.n_objects + 1):  # a dozen vehicles
                fr = sc.frame[sc.visible & (sc.id == v)]
                share[v] = float(run.match.followed_share(v, (int(fr.min()),
                                                               int(fr.max()) + 1))[1])
            res = analyse(TrackPoints.from_log(run.log), settings_from_dict(queue_settings()),
                          sc.fps, sc.n_frames)
            errors = count_errors(movement_counts(res), truth)
            row = {
                "queued_keep_id": sum(share[v] >= 0.99 for v in queued),
                "queued": len(queued),
                "others_keep_id": sum(share[v] >= 0.99 for v in share if v not in queued),
                "others": sc.n_objects - len(queued),
                "queued_share": [round(share[v], 3) for v in queued],
                "movement_abs_error": errors["total"]["abs_error"],
                "movement_errors": {k: v["error"] for k, v in errors.items()
                                    if k != "total" and v["error"]},
                "stop_line": line_counts(res),
            }
            out[f"{seed}/{name}"] = row
            print(f"seed {seed} {name}: queued vehicles keeping one ID "
                  f"{row['queued_keep_id']}/{row['queued']} (shares {row['queued_share']}), "
                  f"others {row['others_keep_id']}/{row['others']}; movement |error| "
                  f"{row['movement_abs_error']} {row['movement_errors']}; stop line "
                  f"{row['stop_line']}", flush=True)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
