"""Stopped vehicles keep their identity (issue 14): paper 1's intersection (X5), whose two
waiting vehicles brake to the stop line, stand still from frame 60 to 300 (8 s at 30 fps) and
drive on. While a vehicle stands it fades into the disturbance-map background, its blob breaks
into fragments at its edges and vanishes; template matching (SPEC §1.1 step 3) must hold its
track, with the same ID, through the whole wait."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("tracker", ["kalman-ca", "default"])
def test_waiting_vehicles_keep_one_id_through_the_wait(tracker: str) -> None:
    from mvtrack.experiments import intersection as x5
    from mvtrack.experiments._video import track_scene
    from mvtrack.experiments.intersection_measure import WAIT
    from mvtrack.sim.intersection import x5_intersection
    from mvtrack.sim.render import render_frames

    scene = x5_intersection(0)
    opts = x5._settings(scene)[tracker]
    run = track_scene(scene, opts["config"], seed=0, frames=list(render_frames(scene, 0)),
                      detector_params=opts["detector_params"])
    for v in scene.ids_of("waiting").tolist():
        tid, share = run.match.followed_share(v, WAIT)
        assert share >= 0.99, f"vehicle {v}: one track follows {share:.0%} of its wait"
        # the same track came with it to the stop line and leaves with it (a second track on
        # a split two-tone vehicle may follow it as well)
        ids, counts, n = run.match.followers(v)
        whole = float(counts[ids == tid][0]) / n
        assert whole >= 0.8, (v, tid, whole)
