"""The video experiments (X4, X5, X8) and the ground-truth matching they rest on."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtrack.experiments._video import breaks, match_to_truth
from mvtrack.experiments.report import write_report
from mvtrack.sim.nine_vehicles import x4_nine_vehicles
from mvtrack.tracking import TrackLog
from mvtrack.types import TrackFrame


def _log_from_truth(scene, relabel) -> TrackLog:
    """A perfect tracker output: the visible truth, with track IDs from ``relabel(frame, id)``."""
    log = TrackLog()
    vis = scene.visible
    for f in range(scene.n_frames):
        rs = scene.rows(f)
        sel = vis[rs]
        ids = scene.id[rs][sel]
        xy = scene.xy[rs][sel] + 1.0  # a 1 px offset, well inside the pairing radius
        n = ids.size
        tid = np.array([relabel(f, int(i)) for i in ids], dtype=np.int64)
        log.append(TrackFrame(f, tid, np.ones(n, np.int64), np.arange(n, dtype=np.int64), xy,
                              xy, xy, scene.wh[rs][sel], np.zeros((n, 2))))
    return log


def test_matching_recovers_identities_coverage_and_breaks() -> None:
    scene = x4_nine_vehicles().truncate(120)

    def relabel(f: int, i: int) -> int:
        if i == 9 and f >= 65:
            return 200  # V9's track breaks at frame 65
        return 100 + i

    m = match_to_truth(scene, _log_from_truth(scene, relabel))
    ids, obj, share = m.majority(5)
    np.testing.assert_array_equal(ids, [101, 102, 103, 104, 105, 106, 107, 108, 109, 200])
    np.testing.assert_array_equal(obj, [1, 2, 3, 4, 5, 6, 7, 8, 9, 9])
    np.testing.assert_allclose(share, 1.0)
    best, cover, n_tracks = m.coverage(1)
    assert (best, cover, n_tracks) == (101, 1.0, 1)
    frames, tracks = m.sequence(9)
    assert breaks(frames, tracks) == [(65, 109, 200)]
    best9, cover9, n9 = m.coverage(9)
    expected = (frames >= 65).sum() / frames.size
    assert n9 == 2 and best9 == (200 if expected > 0.5 else 109)
    assert cover9 == pytest.approx(max(expected, 1 - expected))


def test_matching_leaves_far_rows_unpaired() -> None:
    scene = x4_nine_vehicles().truncate(30)
    log = _log_from_truth(scene, lambda f, i: i)
    moved = TrackLog()
    for tf in log:  # shift every row 30 px: nothing can pair
        xy = tf.filtered_xy + 30.0
        moved.append(TrackFrame(tf.frame, tf.track_id, tf.state, tf.det_index, xy, xy, xy,
                                tf.wh, tf.velocity))
    m = match_to_truth(scene, moved)
    assert (m.gt_track == -1).all() and (m.row_gt == 0).all()
    assert breaks(np.arange(5), np.array([-1, 3, -1, 3, 4])) == [(4, 3, 4)]


@pytest.mark.slow
def test_synthetic_traffic_report(tmp_path, monkeypatch) -> None:
    from mvtrack.experiments import synthetic_traffic as x4

    monkeypatch.setattr(x4, "Q_SWEEP", (0.01,))
    rep = x4.run(runs=1, seed=0)
    f = rep.figures
    assert f["paper"]["tracks"] == {"kalman-ca": 10, "rls": 11}
    assert f["setting"]["r"] == 1.0 and f["setting"]["kf_q"] == 0.1
    # golden, SPEC X4 settings (B₀ = I₀): start-up tracks on the ghosts of V1–V8, then one
    # track per vehicle; V9 is never lost, the KF comes within 1 px of the gate at bend B
    assert f["tracks"] == {"kalman-ca": 23, "rls": 23}
    assert f["startup_tracks"] == {"kalman-ca": 14, "rls": 13}
    for p in ("kalman-ca", "rls"):
        assert f["v9_breaks"][p] == []
        assert all(f["tracks_per_vehicle"][p][v] == 1 for v in (1, 2, 3, 4, 5, 6, 7, 9))
    kf, rls = f["v9_prediction"]["kalman-ca"], f["v9_prediction"]["rls"]
    assert 8.0 < kf["max_error_bend_B"] < 10.0 and rls["max_error_bend_B"] < 6.0
    assert not kf["warmup_at_bend_A"] and not kf["warmup_at_bend_B"]
    v = f["variants"]
    assert v["kalman-ca, primed"]["tracks"] == 9 and v["rls, primed"]["tracks"] == 9
    old = v["kalman-ca, R = 4, q = 0.05"]  # the previous headline: the KF breaks at bend B
    assert [b["where"] for b in old["v9_breaks"]] == ["bend B"]
    assert old["v9_breaks"][0]["prediction_error"] > 10.0
    assert v["kalman-ca, q = 0.01"]["v9_breaks"]
    assert "primed" in f["variant_reasons"]
    # the figures: V9's error profile crosses the dashed 10 px gate only where a track broke
    ax = rep.plots["v9_prediction"].axes[0]
    assert any(tuple(line.get_ydata()) == (10.0, 10.0) for line in ax.lines)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "track breaks" in legend and "KF, R = 4, q = 0.05 (variant)" in legend
    traj = [t.get_text() for t in rep.plots["kalman-ca"].axes[0].get_legend().get_texts()]
    assert traj == ["truth (dashed)", *(f"V{i}" for i in range(1, 10)), "start-up / spurious"]
    paths = write_report(rep, tmp_path)
    data = json.loads((tmp_path / "synthetic-traffic.json").read_text())
    assert data["tracks"] == f["tracks"]
    assert "| quantity | paper |" in (tmp_path / "synthetic-traffic.md").read_text()
    assert any(p.suffix == ".png" for p in paths)


@pytest.mark.slow
def test_intersection_report(monkeypatch) -> None:
    from mvtrack.experiments import intersection as x5

    full = x5._settings

    def fewer(scene):  # the headline settings, the pipeline blob stage and the default
        return {k: v for k, v in full(scene).items() if "NCC" not in k and "templates" not in k}

    monkeypatch.setattr(x5, "_settings", fewer)
    rep = x5.run(runs=1, seed=0)
    f = rep.figures
    assert f["setting"]["blobs"] == {"close_size": 0, "min_area": 20.0}
    kf, rls = f["kalman-ca"], f["rls"]
    assert {c: kf["followed"][c]["n"] for c in x5.CATEGORIES} == {
        "straight": 11, "left": 6, "right": 1, "waiting": 2}
    # golden, seed 0: on the SPEC blob stage both follow every moving vehicle; the one-to-one
    # pairing splits a vehicle's frames between its two tracks for the KF (near-identical
    # estimates) but not for RLS (identical positions, the tie always goes the same way)
    assert kf["followed_moving"]["k"] == 18 and rls["followed_moving"]["k"] == 18
    assert kf["paired_moving"]["k"] <= 8 and rls["paired_moving"]["k"] >= 16
    assert rls["twin_exact_ties_share"] > 0.9 > 0.1 > kf["twin_exact_ties_share"]
    assert kf["twin_frames_share"] > 0.3 and kf["spurious_median"] > 20
    # template matching holds the waiting vehicles' tracks through the wait (it held none
    # before the rescuer searched at the template's box, on smoothed images)
    assert kf["stopped_rows"] > 0 and kf["waiting_keep_id"]["k"] == 2
    v = f["variants"]
    pipe = v["kalman-ca, pipeline blobs"]
    assert pipe["paired_moving"]["k"] >= 16 and pipe["spurious_median"] < 10
    assert pipe["twin_frames_share"] < 0.05
    # 16 of the 18 moving vehicles on seed 0: one left turn and the right turn (a 15 px arc
    # at up to 3 px/frame, about 10 g for a car) outrun the filter; the earlier default's
    # manoeuvring noise of 25 box sizes/s² followed the right turn on this seed (17)
    assert v["default"]["followed_moving"]["k"] >= 16
    lo, hi = kf["followed_moving"]["ci95"]
    assert lo < 1.0 == hi
    # the rate plot: every bar has its Wilson interval
    ax = rep.plots["rates"].axes[0]
    bars = [c for c in ax.containers if hasattr(c, "patches")]
    heights = [p.get_height() for c in bars for p in c.patches]
    segs = [seg for coll in ax.collections for seg in coll.get_segments()]
    assert len(heights) == 10 and len(segs) >= 10
    assert "pipeline blobs" in f["variant_reasons"]
    # counts by the counting module: on the true tracks exactly paper 1's (every movement
    # ends in the video; the two waiting vehicles stand ≥ 2 s)
    assert f["counts_from_true_tracks"] == [{"straight": 11, "left": 6, "right": 1,
                                             "waiting": 2, "u-turn": 0, "incomplete": 0}]
    assert f["counts_exact_runs_true_tracks"] == 1
    got = kf["counts_per_run"][0]
    assert sum(got.values()) > 20 and kf["counts_exact_runs"] == 0  # spurious tracks count
    # the default as mvtrack track runs it (tracked pixels held, merged blobs divided, tracks
    # ending at the image's edge): both waiting vehicles kept, no spurious track
    d = v["default"]
    assert d["waiting_keep_id"]["k"] == 2 and d["spurious_median"] == 0
    assert any(r[0].startswith("counting module") for r in rep.rows)


def test_intersection_default_counts_are_paper_1s(monkeypatch) -> None:
    from mvtrack.experiments import intersection as x5

    full = x5._settings
    monkeypatch.setattr(x5, "_settings", lambda scene: {
        k: v for k, v in full(scene).items() if "NCC" not in k and "templates" not in k})
    f = x5.run(runs=1, seed=0).figures
    d = f["variants"]["default"]
    assert d["counts_per_run"] == f["counts_from_true_tracks"] and d["counts_exact_runs"] == 1


@pytest.mark.slow
def test_splitting_group_report() -> None:
    from mvtrack.experiments import splitting_group as x8

    rep = x8.run(runs=1, seed=0)
    f = rep.figures
    assert f["runs"] == 1 and f["setting"]["blobs"] == {"close_size": 0, "min_area": 20.0}
    for d in x8.DISTANCES:
        s = f[d]
        assert set(s["continues_on"]) == set(x8.OUTCOMES)
        assert sum(r["k"] for r in s["continues_on"].values()) == 1  # one outcome per seed
        # golden, seed 0: the group's track lives through the split and goes with P2/P3;
        # P1 gets his own new track at once, whatever the distance
        assert s["continues_on"]["ends"]["k"] == 0 and s["continues_on"]["P1"]["k"] == 0
        assert s["p1_own_track"]["k"] == 1 and s["latency_frames"]["max"] <= 2
        lo, hi = s["p1_own_track"]["ci95"]
        assert 0.0 < lo < 1.0 == hi
        iso = s["at_isolation_median"]
        assert iso["p1_distance"] > 10.0 > iso["p2_p3_distance"]
    for run_ in f["per_run"]["coupled"]:
        assert run_["p1"]["group_track"] > 0 and run_["p1"]["first_isolated"] >= 60
    assert set(f["variants"]) == {"default", *(f"{d}, {x8.NO_DEPTH}" for d in x8.DISTANCES)}
    assert x8.NO_DEPTH in f["variant_reasons"]
    # the outcome bars are the rates, each with its Wilson interval
    ax = rep.plots["outcomes"].axes[0]
    h = {c.get_label(): [p.get_height() for p in c.patches] for c in ax.containers
         if hasattr(c, "patches") and not c.get_label().startswith("_")}
    assert h[x8.LABELS["coupled"]] == pytest.approx(
        [f["coupled"]["continues_on"][k]["rate"] for k in x8.OUTCOMES])
    segs = [seg for coll in ax.collections for seg in coll.get_segments()]
    assert len(segs) >= 3 * len(x8.OUTCOMES)
    # the close-up shows the truth of P1–P3 beside the tracks
    split = rep.plots["split"].axes[0]
    labels = split.get_legend_handles_labels()[1]
    assert "truth P1–P3" in labels and "the group's track" in labels and "P1's track" in labels
    assert "does not help" in rep.notes or "helps here" in rep.notes
