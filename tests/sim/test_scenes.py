"""Simulated scenes: the geometry of SPEC X4, X5, X7, X8 and the crowd, and the gt rows."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.io.mot import read_mot, write_mot
from mvtrack.sim import scenes as S
from mvtrack.sim.scene import _visibility


def _pair(scene: S.Scene, a: int, b: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    fa, xa = scene.trajectory(a)
    fb, xb = scene.trajectory(b)
    common = np.intersect1d(fa, fb)
    return common, xa[np.isin(fa, common)], xb[np.isin(fb, common)]


# ---------------------------------------------------------------------- X4
def test_x4_v6_v7_closest_approach_is_9_6_px_at_frame_73_without_overlap() -> None:
    sc = S.x4_nine_vehicles()
    frames, a, b = _pair(sc, 6, 7)
    d = np.linalg.norm(a - b, axis=1)
    assert frames[np.argmin(d)] == 73
    assert d.min() == pytest.approx(9.6, abs=1e-9)
    gap = np.abs(a - b)
    assert not np.any((gap[:, 0] < 12) & (gap[:, 1] < 8))  # 12×8 boxes never overlap


def test_x4_crossing_point_is_visited_16_frames_apart() -> None:
    sc = S.x4_nine_vehicles()
    f6, x6 = sc.trajectory(6)
    f7, x7 = sc.trajectory(7)
    np.testing.assert_allclose(x6[f6 == 65][0], [162, 205])
    np.testing.assert_allclose(x7[f7 == 81][0], [162, 205])


def test_x4_formulas_sizes_and_contrast() -> None:
    sc = S.x4_nine_vehicles()
    assert (sc.size, sc.fps, sc.n_frames, sc.n_objects) == ((320, 240), 30.0, 240, 9)
    for i in range(5):
        f, xy = sc.trajectory(i + 1)
        np.testing.assert_allclose(xy, np.column_stack([10 + 1.5 * f, 84 + 16.0 * i + 0 * f]))
    f, xy = sc.trajectory(8)
    np.testing.assert_allclose(xy, np.column_stack([314 - 1.5 * f, 230.0 + 0 * f]))
    np.testing.assert_array_equal(sc.wh, np.tile([12.0, 8.0], (len(sc.frame), 1)))
    assert np.all(np.abs(S.luminance(sc.color) - 96.0) >= 60)
    assert len({tuple(c) for c in sc.color}) == 9


def test_x4_v9_follows_line_arcs_line_at_6_px_per_frame() -> None:
    sc = S.x4_nine_vehicles()
    f, xy = sc.trajectory(9)
    assert f[0] >= 40
    path = S.x9_path()
    assert path.length == pytest.approx(106 + 12 * np.pi + 10 + 4 * np.pi + 198)
    # frame 40 is at (-6, 16), outside the image; the first row is frame 41 at (0, 16).
    np.testing.assert_allclose(xy[f == 41][0], [0.0, 16.0])
    s = 6.0 * (f - 40)
    on_a = (s > 106) & (s < 106 + 12 * np.pi)
    on_b = (s > 116 + 12 * np.pi) & (s < 116 + 16 * np.pi)
    np.testing.assert_allclose(np.linalg.norm(xy[on_a] - [100, 40], axis=1), 24.0)
    np.testing.assert_allclose(np.linalg.norm(xy[on_b] - [132, 50], axis=1), 8.0)
    assert set(f[on_a]) == set(range(58, 64))  # frames ≈ 58–64 on arc A (SPEC X4)
    assert set(f[on_b]) <= set(range(66, 69))  # ≈ 66–68 on arc B
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    first = (s[1:] <= 106) | (s[:-1] >= 116 + 16 * np.pi)  # both ends on a horizontal line
    assert first.sum() > 20
    np.testing.assert_allclose(steps[first], 6.0)
    assert np.all(steps <= 6.0 + 1e-9)  # chords of arcs are shorter


# ---------------------------------------------------------------------- X7
@pytest.mark.parametrize("jitter", [0.0, 0.25])
def test_x7_targets_meet_at_160_120_at_frame_50(jitter: float) -> None:
    sc = S.x7_crossing(3, jitter=jitter)
    assert sc.n_frames == 100
    at50 = sc.xy[sc.frame == 50]
    np.testing.assert_allclose(at50, [[160, 120], [160, 120]], atol=1e-9)
    f1, x1 = sc.trajectory(1)
    f2, x2 = sc.trajectory(2)
    # Both stay on their lines: T1 on (20,220) + τ(2.8,−2), T2 on y = 120.
    np.testing.assert_allclose((x1[:, 0] - 20) / 2.8, (220 - x1[:, 1]) / 2.0, atol=1e-9)
    np.testing.assert_allclose(x2[:, 1], 120.0)
    if jitter == 0:
        np.testing.assert_allclose(x1, np.column_stack([20 + 2.8 * f1, 220 - 2.0 * f1]))
        np.testing.assert_allclose(x2[:, 0], 20 + 2.8 * f2)
    else:
        step = np.diff(x2[:, 0]) / 2.8
        assert 0.15 < step.std() < 0.35  # 25 % along-track speed jitter
        assert abs(step.mean() - 1.0) < 0.1


def test_x7_rejects_negative_jitter() -> None:
    with pytest.raises(ValueError, match="jitter"):
        S.x7_crossing(0, jitter=-0.1)


# ---------------------------------------------------------------------- X5
@pytest.fixture(scope="module")
def x5() -> S.Scene:
    return S.x5_intersection(7)


def test_x5_category_counts_and_directions(x5: S.Scene) -> None:
    counts = {c: len(x5.ids_of(c)) for c in ("straight", "left", "right", "waiting")}
    assert counts == {"straight": 11, "left": 6, "right": 1, "waiting": 2}
    appr = x5.meta["approach"][x5.ids_of("straight") - 1]
    assert np.sum(appr % 2 == 0) == 6 and np.sum(appr % 2 == 1) == 5  # 6 E-W, 5 N-S
    assert (x5.size, x5.fps, x5.n_frames) == ((320, 240), 30.0, 360)


def test_x5_straight_vehicles_keep_to_the_right_hand_lane(x5: S.Scene) -> None:
    # eastbound y = 135, southbound x = 145, westbound y = 105, northbound x = 175
    lane = {0: (1, 135.0), 1: (0, 145.0), 2: (1, 105.0), 3: (0, 175.0)}
    for i in np.concatenate([x5.ids_of("straight"), x5.ids_of("waiting")]):
        axis, value = lane[int(x5.meta["approach"][i - 1])]
        _, xy = x5.trajectory(int(i))
        np.testing.assert_allclose(xy[:, axis], value, atol=1e-9)


def test_x5_waiting_vehicles_stand_still_from_60_to_300(x5: S.Scene) -> None:
    for i in x5.ids_of("waiting"):
        f, xy = x5.trajectory(int(i))
        still = xy[(f >= 60) & (f <= 300)]
        assert len(still) == 241
        assert np.ptp(still, axis=0).max() == 0.0
        before, after = xy[(f >= 50) & (f < 58)], xy[(f > 302) & (f < 320)]
        assert np.all(np.linalg.norm(np.diff(before, axis=0), axis=1) > 0)
        assert np.all(np.linalg.norm(np.diff(after, axis=0), axis=1) > 0)
        # The front of the car is at the stop line, 34 px before the centre.
        assert np.linalg.norm(still[0] - [160, 120]) > 34


def test_x5_turns_by_a_quarter_with_the_stated_radii(x5: S.Scene) -> None:
    for cat, turn, radius in (("left", -np.pi / 2, 40.0), ("right", np.pi / 2, 15.0),
                              ("straight", 0.0, None)):
        for i in x5.ids_of(cat):
            sel = x5.id == i
            hd = np.unwrap(x5.heading[sel])
            assert hd[-1] - hd[0] == pytest.approx(turn, abs=1e-9)
            if radius is not None:
                path = S.x5_path(int(x5.meta["approach"][i - 1]), cat)
                assert path.segments[1][2] == radius


def test_x5_speeds_entries_roads_and_no_overlap(x5: S.Scene) -> None:
    moving = np.concatenate([x5.ids_of(c) for c in ("straight", "left", "right")])
    for i in moving:
        f, xy = x5.trajectory(int(i))
        step = np.linalg.norm(np.diff(xy, axis=0), axis=1)
        v = x5.meta["speed"][i - 1]
        assert 1.5 <= v <= 3.0
        assert np.all(step <= v + 1e-9) and np.all(step > 0.95 * v)  # chords on the arcs
        assert 0 <= x5.meta["entry"][i - 1] <= 300
    x, y = x5.xy[:, 0], x5.xy[:, 1]
    assert np.all(((x >= 130) & (x <= 190)) | ((y >= 90) & (y <= 150)))  # on the roads
    for f in range(x5.n_frames):
        p = x5.xy[x5.rows(f)]
        if len(p) > 1:
            d = np.linalg.norm(p[:, None] - p[None], axis=-1)
            assert d[np.triu_indices(len(p), 1)].min() >= 24.0


def test_x5_is_reproducible_and_seed_dependent() -> None:
    a, b, c = S.x5_intersection(1), S.x5_intersection(1), S.x5_intersection(2)
    np.testing.assert_array_equal(a.xy, b.xy)
    assert a.xy.shape != c.xy.shape or not np.array_equal(a.xy, c.xy)


# ---------------------------------------------------------------------- X8
def test_x8_group_geometry_and_split() -> None:
    sc = S.x8_splitting_group(0)
    assert (sc.size, sc.fps, sc.n_frames, sc.n_objects) == ((320, 240), 15.0, 240, 14)
    xy = {i: sc.trajectory(i) for i in (1, 2, 3)}
    p = {i: xy[i][1][xy[i][0] == 0][0] for i in (1, 2, 3)}
    np.testing.assert_allclose(p[2], [18, 12])
    np.testing.assert_allclose(np.linalg.norm(p[1] - p[2]), 9.0)
    assert p[1][0] > p[2][0] and p[1][1] < p[2][1]  # P1 upper-right
    np.testing.assert_allclose(xy[2][1][xy[2][0] == 60][0], [90, 60])
    for i, v in zip((1, 2, 3), ([1.44, 0.46], [0.25, 1.4], [-0.15, 1.4]), strict=True):
        f, q = xy[i]
        after = (f >= 60) & (f < 100)
        np.testing.assert_allclose(np.diff(q[after], axis=0), np.tile(v, (after.sum() - 1, 1)))
    # The car hides at most the lower half of each person (SPEC X8 as revised): the group is
    # visible in every frame, and exactly half hidden where a person stands behind the car.
    group = np.isin(sc.id, [1, 2, 3])
    assert np.all(sc.visibility[group & (sc.frame < 120)] >= S.VISIBLE_MIN)
    row = (sc.frame == 60) & (sc.id == 2)
    assert sc.visibility[row][0] == pytest.approx(0.5)
    early = group & (sc.frame == 20)
    np.testing.assert_allclose(sc.visibility[early], 1.0)
    occ = sc.meta["occluders"][0]
    assert occ["wh"] == (44.0, 22.0) and occ["xy"] == (96.0, 64.0)
    assert occ["hides"] == "lower half"


def test_lower_half_occluder_hides_only_the_lower_half_of_boxes_behind_it() -> None:
    occ = [{"xy": (50.0, 50.0), "wh": (40.0, 20.0), "hides": "lower half"}]  # y in [40, 60]
    full = [{"xy": (50.0, 50.0), "wh": (40.0, 20.0)}]
    xy = np.array([[50.0, 44.0], [50.0, 40.0], [50.0, 55.0], [200.0, 50.0]])
    wh = np.tile([8.0, 16.0], (4, 1))
    _, vis = _visibility(xy, wh, (320, 240), occ)
    # behind the car (feet at 52, 48): the part of the lower half inside it; in front (feet at
    # 63, below the car's edge at 60): nothing; far away: nothing
    np.testing.assert_allclose(vis, [0.5, 1.0 - 8 * 8 / 128, 1.0, 1.0])
    _, vis_full = _visibility(xy, wh, (320, 240), full)
    np.testing.assert_allclose(vis_full, [1 - 8 * 12 / 128, 1 - 8 * 8 / 128, 1 - 8 * 13 / 128,
                                          1.0])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_x8_others_keep_30_px_from_the_group(seed: int) -> None:
    sc = S.x8_splitting_group(seed)
    cats = [str(c) for c in sc.category[3:]]
    assert cats.count("car") == 6 and cats.count("motorcycle") == 2
    assert cats.count("pedestrian") == 3
    for j in range(4, 15):
        for g in (1, 2, 3):
            _, a, b = _pair(sc, j, g)
            if len(a):
                assert np.linalg.norm(a - b, axis=1).min() >= 30.0
        sel = sc.id == j  # never behind (or over) the static car
        lo, hi = sc.xy[sel] - sc.wh[sel] / 2, sc.xy[sel] + sc.wh[sel] / 2
        assert np.all((hi[:, 0] < 74) | (lo[:, 0] > 118) | (hi[:, 1] < 53) | (lo[:, 1] > 75))
    cars = sc.ids_of("car")
    wh = sc.wh[np.isin(sc.id, cars)]
    assert np.all(np.isclose(np.sort(wh, axis=1), [12.0, 28.0]))


# ---------------------------------------------------------------------- crowd
@pytest.mark.parametrize("clamp", [False, True])
def test_crowd_stays_inside_with_bounded_speed_and_sizes(clamp: bool) -> None:
    sc = S.crowd(300, frames=200, seed=4, clamp_speed=clamp)
    lo, hi = sc.xy - sc.wh / 2, sc.xy + sc.wh / 2
    assert lo.min() >= 0 and np.all(hi <= np.array([1920, 1080]))
    assert len(sc.frame) == 300 * 200 and np.all(sc.visible)
    xy = sc.xy.reshape(200, 300, 2)
    step = np.linalg.norm(np.diff(xy, axis=0), axis=-1)
    wh = sc.body
    # Away from the borders (no reflection) a step is the current speed.
    inner = np.all((xy[1:] > wh + 8) & (xy[1:] < np.array([1920, 1080]) - wh - 8), axis=-1)
    first = step[0][inner[0]]  # initial speeds: uniform in [1, 6] (+ one frame of a)
    assert first.min() >= 0.8 and first.max() <= 6.2
    assert first.min() < 1.5 and first.max() > 5.5
    if clamp:
        assert step.max() <= 6.0 + 1e-9 and step[inner].min() >= 1.0 - 1e-9
    else:  # a random walk of σ = 0.05·√k per axis: rarely beyond 1–6 by more than 2 px/frame
        assert step.max() <= 8.0 and step.max() > 6.0
    assert 0.9 * 40 <= wh[:, 0].min() and wh[:, 0].max() <= 1.1 * 40
    assert 0.9 * 30 <= wh[:, 1].min() and wh[:, 1].max() <= 1.1 * 30
    # White acceleration σ = 0.05: second differences away from the borders (and limits).
    acc = np.diff(xy, 2, axis=0)
    ok = inner[1:] & inner[:-1]
    if clamp:
        ok &= (step[1:] > 1.2) & (step[1:] < 5.8) & (step[:-1] > 1.2) & (step[:-1] < 5.8)
    assert np.std(acc[ok]) == pytest.approx(0.05, rel=0.1)


def test_crowd_ten_thousand_targets() -> None:
    sc = S.crowd(10_000, frames=5, seed=0)
    assert sc.n_objects == 10_000 and len(sc.frame) == 50_000


@pytest.mark.parametrize("kwargs", [{"n": 0}, {"n": 5, "frames": 0}, {"n": 5, "size": (30, 20)}])
def test_crowd_rejects_bad_values(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        S.crowd(**kwargs)


# ---------------------------------------------------------------------- gt rows and registry
def test_gt_mot_rows_round_trip_through_the_mot_reader(tmp_path) -> None:
    sc = S.x8_splitting_group(0)
    rows = sc.gt_mot()
    assert rows.shape == (int(sc.visible.sum()), 9)
    np.testing.assert_array_equal(rows[:, 0], sc.frame[sc.visible] + 1)
    np.testing.assert_allclose(rows[:, 2:4] + rows[:, 4:6] / 2, sc.xy[sc.visible])
    assert sc.gt_mot(include_hidden=True).shape[0] == len(sc.frame)
    table = read_mot(write_mot(tmp_path / "gt.txt", rows, "gt"), "gt")
    order = np.lexsort((table.id, table.frame))
    np.testing.assert_array_equal(table.frame[order], sc.frame[sc.visible])
    np.testing.assert_allclose(table.tlwh[order], rows[:, 2:6], atol=1e-3)
    assert set(table.cls) == {1, 3, 5}


def test_build_by_name_and_errors() -> None:
    assert S.build("x4", frames=10).n_frames == 10
    assert S.build("crowd", n=7, frames=3).n_objects == 7
    with pytest.raises(ValueError, match="unknown scene"):
        S.build("x9")
    with pytest.raises(ValueError, match="crowd"):
        S.build("x5", n=3)
    with pytest.raises(ValueError, match="frames"):
        S.build("x7", frames=101)
