"""Drawings: gate ellipses land where the gate's boundary is, boxes carry their state colour."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mvtrack.association.gate import Gate, GateRegions
from mvtrack.types import TrackFrame, TrackState
from mvtrack.viz.annotate import (
    GATE_COLOR,
    STATE_COLORS,
    TrailBuffer,
    annotate_frame,
    draw_boxes,
    draw_gates,
    ellipse_points,
    gate_ellipses,
    shown_gates,
)
from mvtrack.viz.plots import TrackRows, save_figure, trajectory_figure


def _frame(k: int, ids, states, xy, wh=(10.0, 8.0)) -> TrackFrame:
    n = len(ids)
    xy = np.asarray(xy, dtype=float).reshape(n, 2)
    return TrackFrame(
        frame=k,
        track_id=np.asarray(ids, dtype=np.int64),
        state=np.asarray(states, dtype=np.int64),
        det_index=np.arange(n, dtype=np.int64),
        measured_xy=xy.copy(),
        filtered_xy=xy.copy(),
        predicted_xy=xy.copy(),
        wh=np.broadcast_to(np.asarray(wh, float), (n, 2)).copy(),
        velocity=np.zeros((n, 2)),
    )


def _lit(img: np.ndarray) -> np.ndarray:
    return img.any(axis=2)


def test_gate_ellipses_match_eigendecomposition() -> None:
    rng = np.random.default_rng(3)
    a = rng.normal(size=(50, 2, 2))
    cov = a @ a.transpose(0, 2, 1) + 0.1 * np.eye(2)
    axes, angle = gate_ellipses(cov, 9.21)
    lam, vec = np.linalg.eigh(cov)  # ascending
    np.testing.assert_allclose(axes[:, 0], np.sqrt(9.21 * lam[:, 1]), rtol=1e-10)
    np.testing.assert_allclose(axes[:, 1], np.sqrt(9.21 * lam[:, 0]), rtol=1e-10)
    major = vec[:, :, 1]
    direction = np.stack([np.cos(np.radians(angle)), np.sin(np.radians(angle))], axis=1)
    np.testing.assert_allclose(np.abs((major * direction).sum(axis=1)), 1.0, atol=1e-9)


def test_ellipse_points_lie_on_the_gate_boundary() -> None:
    rng = np.random.default_rng(4)
    a = rng.normal(size=(20, 2, 2))
    cov = a @ a.transpose(0, 2, 1) + 0.5 * np.eye(2)
    center = rng.uniform(0, 100, size=(20, 2))
    axes, angle = gate_ellipses(cov, 4.0)
    pts = ellipse_points(center, axes, angle, n_points=24)
    d = pts - center[:, None, :]
    r2 = np.einsum("kpi,kij,kpj->kp", d, np.linalg.inv(cov), d)
    np.testing.assert_allclose(r2, 4.0, rtol=1e-9)


def test_circle_gate_is_drawn_at_its_radius() -> None:
    img = np.zeros((120, 120, 3), np.uint8)
    draw_gates(img, np.array([[60.0, 60.0]]), np.eye(2)[None], 20.0**2)
    lit = _lit(img)
    # the four extreme points of a radius-20 circle are drawn, centre and far pixels are not
    for x, y in [(80, 60), (40, 60), (60, 80), (60, 40)]:
        assert lit[y - 1 : y + 2, x - 1 : x + 2].any(), (x, y)
    assert not lit[55:66, 55:66].any()
    assert not lit[60, 90] and not lit[60, 30]
    ys, xs = np.nonzero(lit)
    radius = np.hypot(xs - 60, ys - 60)
    assert 18.3 < radius.min() and radius.max() < 21.8
    assert tuple(img[ys[0], xs[0]]) != (0, 0, 0)
    assert np.all(img[lit][:, 2] > 0)  # yellow: red channel on (BGR)
    assert GATE_COLOR[2] > 0


def test_rotated_gate_ellipse_is_drawn_along_its_major_axis() -> None:
    # major axis at 45° (image coordinates), semi-axes 30 and 8
    th = np.radians(45.0)
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    cov = rot @ np.diag([30.0**2, 8.0**2]) @ rot.T
    img = np.zeros((160, 160, 3), np.uint8)
    draw_gates(img, np.array([[80.0, 80.0]]), cov[None], 1.0)
    lit = _lit(img)
    tip = np.rint(80 + 30 * np.array([np.cos(th), np.sin(th)])).astype(int)
    assert lit[tip[1] - 1 : tip[1] + 2, tip[0] - 1 : tip[0] + 2].any()
    side = np.rint(80 + 8 * np.array([-np.sin(th), np.cos(th)])).astype(int)
    assert lit[side[1] - 1 : side[1] + 2, side[0] - 1 : side[0] + 2].any()
    # along the image x axis the boundary is much closer than 30 px
    assert not lit[80, 108:112].any()
    ys, xs = np.nonzero(lit)
    d = np.stack([xs - 80.0, ys - 80.0], axis=1)
    r2 = np.einsum("pi,ij,pj->p", d, np.linalg.inv(cov), d)
    assert np.all(np.abs(np.sqrt(r2) - 1.0) < 0.2)


def test_drawn_gate_regions_agree_with_each_distance() -> None:
    """The regions :meth:`Gate.regions` gives to draw lie where each quadratic distance
    (:mod:`mvtrack.association.distances`, computed apart from the gate) equals its gate."""
    from mvtrack.association import distances

    rng = np.random.default_rng(7)
    k = 12
    xy = rng.uniform(50, 200, size=(k, 2))
    p = rng.uniform(2, 9, size=k)
    cov = p[:, None, None] * np.eye(2)
    S = cov + 4.0 * np.eye(2)
    vel = rng.normal(scale=2.0, size=(k, 2))
    vel[0] = [0.1, 0.0]  # slow: eq. (9) fallback
    view = distances.TrackView(xy, cov, S, vel, np.zeros((k, 2)))
    for name in ("euclidean", "uncoupled", "coupled", "mahalanobis"):
        gate = distances.default_gate(name)
        regions = Gate.build(name, view, gate).regions(np.arange(k), np.arange(k) + 1)
        np.testing.assert_array_equal(regions.center, xy)
        assert regions.r2 == gate and regions.track_id.tolist() == list(range(1, k + 1))
        axes, angle = gate_ellipses(regions.shape, regions.r2)
        pts = ellipse_points(regions.center, axes, angle, n_points=16)
        det = pts.reshape(-1, 2)
        ti = np.repeat(np.arange(k), 16)
        dj = np.arange(k * 16)
        value = distances.pair_distance(name, view, det, ti, dj)
        np.testing.assert_allclose(value, gate, rtol=1e-8, err_msg=name)


def test_boxes_carry_the_colour_of_their_state() -> None:
    img = np.zeros((100, 200, 3), np.uint8)
    tf = _frame(
        0, [1, 2, 3], [TrackState.CONFIRMED, TrackState.COASTING, TrackState.STOPPED],
        [[30, 50], [100, 50], [170, 50]], wh=(20, 20),
    )
    draw_boxes(img, tf, thickness=1, labels=False)
    for (x, _), state in zip(tf.filtered_xy, tf.state, strict=True):
        # left edge of the box at x - 10, y = 50
        px = img[50, int(x) - 10]
        assert tuple(int(c) for c in px) == STATE_COLORS[int(state)]
    assert not img[50, 30].any()  # box interior untouched


def test_trails_follow_each_id_in_time_order() -> None:
    trails = TrailBuffer(length=3)
    for k in range(5):
        trails.push(_frame(k, [7, 2], [1, 1], [[10 + k, 5], [50, 5 + 2 * k]]))
    ids, lines = trails.polylines()
    assert list(ids) == [2, 7]
    np.testing.assert_array_equal(lines[0], [[50, 9], [50, 11], [50, 13]])
    np.testing.assert_array_equal(lines[1], [[12, 5], [13, 5], [14, 5]])
    trails.push(_frame(5, [7], [1], [[15, 5]]))  # track 2 has ended: its trail goes
    ids, lines = trails.polylines()
    assert list(ids) == [7]
    np.testing.assert_array_equal(lines[0], [[13, 5], [14, 5], [15, 5]])
    empty = TrailBuffer(length=4)
    empty.push(_frame(0, [], [], np.zeros((0, 2))))
    empty.push(_frame(1, [3], [1], [[np.nan, np.nan]]))
    assert empty.polylines()[1] == []
    with pytest.raises(ValueError, match="trail length"):
        TrailBuffer(length=1)


def test_gates_are_drawn_only_for_the_confirmed_tracks_with_a_box() -> None:
    ids = np.array([4, 5, -6, 7, 9], np.int64)  # 9 is not in the frame, -6 is tentative
    gates = GateRegions(uid=np.arange(5), track_id=ids, center=np.zeros((5, 2)),
                        shape=np.broadcast_to(np.eye(2), (5, 2, 2)).copy(), r2=9.21)
    tf = _frame(0, [4, 5, -6, 7], [1, 1, 0, 1], [[10, 10], [np.nan, np.nan], [30, 30], [40, 40]])
    assert list(shown_gates(gates, tf).track_id) == [4, 7]


def test_a_relinked_track_keeps_its_gate_under_its_shown_id() -> None:
    # the tracker's track 9 is shown as 2 (relinked to an ended track); 5 is shown as itself
    gates = GateRegions(uid=np.arange(3), track_id=np.array([9, 5, -1], np.int64),
                        center=np.array([[20.0, 20.0], [50.0, 50.0], [0.0, 0.0]]),
                        shape=np.broadcast_to(np.eye(2), (3, 2, 2)).copy(), r2=9.21)
    tf = _frame(0, [2, 5], [1, 1], [[20, 20], [50, 50]])
    assert list(shown_gates(gates, tf).track_id) == [5]  # the IDs compared as they are

    def shown(ids: np.ndarray) -> np.ndarray:
        return np.where(ids == 9, 2, ids)

    g = shown_gates(gates, tf, shown)
    assert list(g.track_id) == [2, 5]
    np.testing.assert_array_equal(g.center, [[20, 20], [50, 50]])


def test_annotate_frame_leaves_input_untouched_and_draws() -> None:
    frame = np.full((60, 80, 3), 40, np.uint8)
    tf = _frame(0, [1], [TrackState.CONFIRMED], [[40, 30]])
    out = annotate_frame(frame, tf, gate_center=tf.predicted_xy, gate_cov=np.eye(2)[None],
                         gate_r2=100.0, text=["frame 0"])
    assert (frame == 40).all()
    assert (out != 40).any(axis=2).sum() > 50
    none = annotate_frame(frame, _frame(1, [], [], np.zeros((0, 2))), gate_center=np.zeros((0, 2)),
                          gate_cov=np.zeros((0, 2, 2)), gate_r2=np.zeros(0))
    assert (none == 40).all()
    grey = annotate_frame(frame[..., 0], tf)
    assert grey.shape == (60, 80, 3)


def test_trajectory_figure_and_rows(tmp_path) -> None:
    frames = [_frame(k, [1, 2], [1, 2], [[10 + k, 20], [60, 20 + k]]) for k in range(10)]
    rows = TrackRows.from_frames(frames)
    assert len(rows) == 20
    ids, paths, frames_of = rows.split()
    assert list(ids) == [1, 2] and paths[0].shape == (10, 2)
    np.testing.assert_array_equal(frames_of[1], np.arange(10))
    assert rows.state_histogram()["coasting"] == 10
    fig = trajectory_figure(rows, (100, 80), background=np.zeros((80, 100, 3), np.uint8))
    save_figure(fig, tmp_path / "traj.png")
    img = cv2.imread(str(tmp_path / "traj.png"))
    assert img.ndim == 3 and min(img.shape[:2]) > 80  # the figure holds the 100 × 80 frame
    # the two trajectories are drawn in colour on the black frame (no colour without tracks)
    assert np.count_nonzero(img.max(axis=2).astype(int) - img.min(axis=2) > 60) > 100
    assert sorted(p.name for p in tmp_path.iterdir()) == ["traj.png"]


def test_annotate_frame_draws_the_gate_it_is_given_and_only_that() -> None:
    """One gate per track (there is no second stage to draw): a 10 px circle in the gate
    colour, nothing else in it beyond the box."""
    frame = np.zeros((100, 100, 3), np.uint8)
    tf = _frame(0, [1], [TrackState.CONFIRMED], [[50, 50]], wh=(4, 4))
    out = annotate_frame(frame, tf, gate_center=np.array([[50.0, 50.0]]),
                         gate_cov=np.eye(2)[None], gate_r2=10.0**2)
    inner = np.nonzero(np.abs(out.astype(int) - GATE_COLOR).sum(axis=2) < 60)
    r = np.hypot(inner[1] - 50, inner[0] - 50)
    assert r.size > 30 and np.median(r) == pytest.approx(10.0, abs=1.0)
    none = annotate_frame(frame, tf)
    assert not (np.abs(none.astype(int) - GATE_COLOR).sum(axis=2) < 60).any()
    # what the gate adds to the drawing is the circle, nothing farther out or nearer in
    ys, xs = np.nonzero((out != none).any(axis=2))
    r = np.hypot(xs - 50, ys - 50)
    assert r.size > 30 and 8.5 < r.min() and r.max() < 11.5


# ------------------------------------------------------------ labels readable in the frame
def _dark_boxes(img: np.ndarray) -> list[tuple[int, int, int, int]]:
    """x0, y0, x1, y1 (inclusive) of each connected patch of the labels' dark fill."""
    dark = (img == 20).all(axis=2).astype(np.uint8)
    _, _, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=8)
    return [(x, y, x + w - 1, y + h - 1) for x, y, w, h, area in stats[1:] if area > 20]


def _inside(a: tuple[int, ...], b: tuple[int, ...]) -> bool:
    return a[0] >= b[0] and a[1] >= b[1] and a[2] <= b[2] and a[3] <= b[3]


def test_place_frame_labels_never_overlap_and_stay_in_the_frame() -> None:
    from mvtrack.viz.labels import place_frame_labels

    rng = np.random.default_rng(11)
    for _ in range(50):
        k = int(rng.integers(1, 12))
        xy = rng.uniform([-10, -10], [330, 250], size=(k, 2))
        wh = rng.uniform(6, 40, size=(k, 2))
        boxes = np.rint(np.concatenate([xy - wh / 2, xy + wh / 2], axis=1)).astype(np.int64)
        sizes = rng.integers([12, 10], [30, 14], size=(k, 2))
        banner = np.array([[2, 2, 120, 16], [2, 17, 170, 31]])
        corner = place_frame_labels(boxes, sizes, (320, 240), banner)
        rect = np.concatenate([corner, corner + sizes], axis=1)
        assert (rect[:, :2] >= 0).all() and (rect[:, 2] <= 320).all() and (rect[:, 3] <= 240).all()
        if k <= 4:  # few labels always find a free place around a box
            allr = np.vstack([banner, rect])
            for i in range(2, len(allr)):
                for j in range(i):
                    apart = (allr[i, 0] > allr[j, 2] or allr[j, 0] > allr[i, 2]
                             or allr[i, 1] > allr[j, 3] or allr[j, 1] > allr[i, 3])
                    assert apart, (i, j, allr)


def test_ids_near_the_header_and_side_by_side_stay_readable() -> None:
    """A box under the frame's header and two boxes side by side: every ID gets its own dark
    label, apart from the header and from each other, with its digits on it."""
    img = np.full((240, 320, 3), 120, np.uint8)
    tracks = _frame(5, [9, 4, 5], [int(TrackState.CONFIRMED)] * 3,
                    [[60, 30], [200, 120], [212, 120]], wh=(10, 24))
    text = ["frame 5  tracks 3", "kalman-cv | euclidean | optimal"]
    out = annotate_frame(img, tracks, text=text)
    boxes = _dark_boxes(out)
    header = [b for b in boxes if b[0] <= 4]
    labels = [b for b in boxes if b[0] > 4]
    assert len(labels) == 3, boxes
    b, g, r = (out[..., c].astype(int) for c in range(3))
    green = (g > 100) & (g > r + 40) & (g > b + 40)  # the confirmed colour, anti-aliased
    for lab in labels:
        x0, y0, x1, y1 = lab
        assert green[y0 : y1 + 1, x0 : x1 + 1].sum() >= 5  # the digits are drawn on it
        for h in header:
            assert lab[0] > h[2] or lab[1] > h[3] or lab[3] < h[1]
    # the label of track 9 (box x 55..65, y 18..42) is not under the header: below its box
    nine = [b for b in labels if b[0] < 100]
    assert len(nine) == 1 and nine[0][1] > max(h[3] for h in header)
