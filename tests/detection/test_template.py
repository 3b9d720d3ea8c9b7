"""Template matching for stopped vehicles (SPEC §1.1 step 3, [R]: NCC ≥ 0.8 in the gate)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection.template import TemplateBank
from mvtrack.video.rescue import TemplateRescuer, search_radii

H, W = 120, 160
VW, VH = 18, 12  # vehicle box


def _vehicle(seed: int = 3) -> np.ndarray:
    """A two-tone textured 'vehicle' (NCC needs texture)."""
    rng = np.random.default_rng(seed)
    v = np.full((VH, VW), 60, np.uint8)
    v[:, VW // 2 :] = 170
    v[3:9, 4:14] = 230  # windows
    return np.clip(v + rng.normal(0, 6, v.shape), 0, 255).astype(np.uint8)


def _frame(tl: tuple[int, int] | None, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    img = np.clip(rng.normal(110, 4, (H, W)), 0, 255).astype(np.uint8)
    if tl is not None:
        x, y = tl
        img[y : y + VH, x : x + VW] = _vehicle()
    return np.dstack([img] * 3)


def _centre(tl: tuple[int, int]) -> np.ndarray:
    return np.array([tl[0] + (VW - 1) / 2, tl[1] + (VH - 1) / 2])


def _bank() -> TemplateBank:
    """A bank without the travel guard and without smoothing (the bare NCC of SPEC §1.1 [R]),
    for tests of the search itself."""
    return TemplateBank(min_travel=0, min_travel_px=0, min_hits=0, max_drift=None, smooth=0)


def _bank_with_vehicle(tl=(50, 40), uid: int = 7) -> TemplateBank:
    bank = _bank()
    bank.observe(_frame(tl, seed=1), [uid], [_centre(tl)], [[VW, VH]])
    return bank


def test_rescue_finds_a_stopped_vehicle_at_its_true_centre() -> None:
    tl = (50, 40)
    bank = _bank_with_vehicle(tl)
    # new noise, same place; the prediction is off by (6, −4) px, inside the 20 px gate
    found, xy, score = bank.rescue(
        _frame(tl, seed=2), [7], [_centre(tl) + np.array([6, -4])], [[VW, VH]]
    )
    assert found.tolist() == [True]
    assert score[0] >= 0.8
    np.testing.assert_allclose(xy[0], _centre(tl), atol=0.01)


def test_rescue_rejects_a_blank_region() -> None:
    tl = (50, 40)
    bank = _bank_with_vehicle(tl)
    found, xy, score = bank.rescue(_frame(None, seed=2), [7], [_centre(tl)], [[VW, VH]])
    assert found.tolist() == [False]
    assert np.isnan(xy).all()
    assert score[0] < 0.5  # best correlation with road noise is low


def test_rescue_searches_only_inside_the_circular_gate() -> None:
    bank = _bank_with_vehicle((50, 40))
    moved = (50 + 16, 40 + 16)  # 22.6 px away: outside a 20 px circle, inside its square
    frame = _frame(moved, seed=2)
    pred = _centre((50, 40))
    found, _, _ = bank.rescue(frame, [7], [pred], gate_radius=20)
    assert not found[0]
    found, xy, _ = bank.rescue(frame, [7], [pred], gate_radius=23)
    assert found[0]
    np.testing.assert_allclose(xy[0], _centre(moved), atol=0.01)
    # a radius per track: the same search
    bank.observe(_frame((10, 80), seed=1), [8], [_centre((10, 80))], [[VW, VH]])
    two = _frame(moved, seed=2)
    two[80 : 80 + VH, 40 : 40 + VW] = _vehicle()[:, :, None]  # 30 px off its prediction
    for radii, want in (([23.0, 31.0], [True, True]), ([20.0, 31.0], [False, True]),
                        ([23.0, 20.0], [True, False])):
        found, _, _ = bank.rescue(two, [7, 8], [pred, _centre((10, 80))], gate_radius=radii)
        assert found.tolist() == want, radii


def test_only_the_tracks_with_templates_are_searched_and_order_is_kept() -> None:
    bank = _bank()
    a, b = (20, 20), (100, 80)
    img = _frame(a, seed=1)
    img[b[1] : b[1] + VH, b[0] : b[0] + VW] = 255 - _vehicle()[..., None]
    bank.observe(img, [5, 2], [_centre(a), _centre(b)], [[VW, VH]] * 2)
    frame = img.copy()
    found, xy, _ = bank.rescue(frame, [2, 99, 5], [_centre(b), [60, 60], _centre(a)])
    assert found.tolist() == [True, False, True]
    np.testing.assert_allclose(xy[[0, 2]], [_centre(b), _centre(a)], atol=0.01)


def test_search_window_clipped_at_the_border_and_skipped_when_leaving_the_image() -> None:
    tl = (3, 2)  # vehicle near the corner; prediction up-left of it, template still inside
    bank = _bank_with_vehicle(tl)
    found, xy, _ = bank.rescue(_frame(tl, seed=2), [7], [_centre(tl) - 2])
    assert found[0]
    np.testing.assert_allclose(xy[0], _centre(tl), atol=0.01)
    # predicted so that the template would stick out of the image: leaving, not searched
    found, _, score = bank.rescue(_frame(tl, seed=2), [7], [_centre(tl) - 4])
    assert not found[0] and np.isnan(score[0])
    # prediction far outside the image: not found, no error
    found, _, score = bank.rescue(_frame(tl, seed=2), [7], [[-200.0, -200.0]])
    assert not found[0] and np.isnan(score[0])


def test_template_is_refreshed_when_the_track_is_detected_again() -> None:
    bank = _bank_with_vehicle((50, 40))
    first = bank.template(7)
    assert first is not None and first.shape == (VH, VW)
    # detected again elsewhere with a different look: the template follows
    img = _frame(None, seed=4)
    img[10 : 10 + VH, 10 : 10 + VW] = 255 - _vehicle()[..., None]
    bank.observe(img, [7], [_centre((10, 10))], [[VW, VH]])
    second = bank.template(7)
    np.testing.assert_array_equal(second, 255 - _vehicle())
    assert not np.array_equal(first, second)


def test_flat_or_tiny_boxes_keep_no_template() -> None:
    bank = _bank()
    flat = np.full((H, W, 3), 90, np.uint8)
    bank.observe(flat, [1, 2], [[50, 50], [80, 80]], [[20, 20], [2, 2]])
    assert bank.template(1) is None and bank.template(2) is None
    found, _, _ = bank.rescue(flat, [1, 2], [[50, 50], [80, 80]])
    assert not found.any()


def test_drop_and_retain_forget_deleted_tracks() -> None:
    bank = _bank()
    img = _frame((50, 40), seed=1)
    bank.observe(img, [3, 1, 2], [_centre((50, 40))] * 3, [[VW, VH]] * 3)
    assert bank.uids.tolist() == [1, 2, 3]
    bank.drop([2])
    assert bank.uids.tolist() == [1, 3] and 2 not in bank and 3 in bank
    bank.retain([3, 42])
    assert bank.uids.tolist() == [3]
    assert bank.rescue(img, [1], [_centre((50, 40))])[0].tolist() == [False]


def test_bind_gives_the_tracker_callback_signature() -> None:
    tl = (50, 40)
    bank = _bank_with_vehicle(tl)
    rescue = bank.bind(_frame(tl, seed=2), gate_radius=10)
    found, xy = rescue(np.array([7]), np.array([_centre(tl) + 3]), np.array([[VW, VH]]))
    assert found.tolist() == [True] and xy.shape == (1, 2)


def test_only_tracks_that_travelled_and_were_seen_often_are_searched() -> None:
    # a track that never moved (clutter, a ghost) would match the static scene for ever
    bank = TemplateBank()  # min_travel = 1 box length and ≥ 10 px, min_hits = 5
    still = (50, 40)
    for k in range(8):
        bank.observe(_frame(still, seed=k), [7], [_centre(still)], [[VW, VH]])
    assert bank.eligible.tolist() == [False]
    assert not bank.rescue(_frame(still, seed=9), [7], [_centre(still)])[0][0]
    # the same vehicle arriving from 20 px away (> its 18 px length) is searched
    bank = TemplateBank()
    for x in range(30, 51, 2):
        bank.observe(_frame((x, 40), seed=x), [7], [_centre((x, 40))], [[VW, VH]])
    assert bank.eligible.tolist() == [True]
    assert bank.rescue(_frame(still, seed=9), [7], [_centre(still)])[0][0]
    # ... but not after only 4 detections, however far it went
    bank = TemplateBank()
    for x in range(20, 51, 10):
        bank.observe(_frame((x, 40), seed=x), [7], [_centre((x, 40))], [[VW, VH]])
    assert bank.eligible.tolist() == [False]


def test_only_tracks_predicted_where_they_were_last_seen_are_searched() -> None:
    tl = (50, 40)
    bank = TemplateBank(min_travel=0, min_travel_px=0, min_hits=0)  # max_drift = 5 px
    bank.observe(_frame(tl, seed=1), [7], [_centre(tl)], [[VW, VH]])
    frame = _frame(tl, seed=2)
    assert bank.rescue(frame, [7], [_centre(tl) + np.array([3.0, -3.0])])[0][0]  # 4.2 px
    # predicted 8 px on: a moving object that was missed, left to the tracker to coast
    found, _, score = bank.rescue(frame, [7], [_centre(tl) + np.array([8.0, 0.0])])
    assert not found[0] and np.isnan(score[0])


def test_a_shrinking_detection_keeps_the_last_full_appearance() -> None:
    tl = (50, 40)
    bank = _bank()
    bank.observe(_frame(tl, seed=1), [7], [_centre(tl)], [[VW, VH]])
    # the blob fades to a fragment (a quarter of the box): the template stays the full box
    bank.observe(_frame(tl, seed=2), [7], [_centre(tl) + 2], [[VW / 2, VH / 2]])
    bank.observe(_frame(tl, seed=3), [7], [_centre(tl) + 2], [[VW / 2, VH / 2]])
    assert bank.template(7).shape == (VH, VW)
    found, xy, _ = bank.rescue(_frame(tl, seed=4), [7], [_centre(tl)])
    assert found[0]
    np.testing.assert_allclose(xy[0], _centre(tl), atol=0.01)
    # with min_fill = 0 every detection refreshes it
    bank = TemplateBank(min_travel=0, min_travel_px=0, min_hits=0, max_drift=None, min_fill=0)
    bank.observe(_frame(tl, seed=1), [7], [_centre(tl)], [[VW, VH]])
    bank.observe(_frame(tl, seed=2), [7], [_centre(tl)], [[VW / 2, VH / 2]])
    assert bank.template(7).shape == (VH // 2, VW // 2)


def test_object_mask_stops_a_template_matching_the_scene_its_object_left() -> None:
    # a strong edge of the scene inside the box, a small textured object on its dark side
    rng = np.random.default_rng(0)
    scene = np.full((80, 80), 50, np.uint8)
    scene[:, 40:] = 200
    scene = np.clip(scene + rng.normal(0, 2, scene.shape), 0, 255).astype(np.uint8)
    with_obj = scene.copy()
    with_obj[36:46, 28:38] = rng.integers(90, 160, (10, 10))
    mask = np.zeros_like(scene)
    mask[36:46, 28:38] = 255
    empty = np.clip(scene + rng.normal(0, 2, scene.shape), 0, 255).astype(np.uint8)
    box = ([40.0, 40.5], [30, 30])  # the object's detected box, edge included
    plain = _bank()
    plain.observe(with_obj, [1], [box[0]], [box[1]])
    masked = _bank()
    masked.min_pixels = 50
    masked.observe(with_obj, [1], [box[0]], [box[1]], mask=mask)
    f_plain, _, s_plain = plain.rescue(empty, [1], [box[0]])
    f_mask, _, s_mask = masked.rescue(empty, [1], [box[0]])
    assert f_plain[0] and s_plain[0] > 0.8  # the edge alone matches the whole-box template
    assert not f_mask[0] and s_mask[0] < 0.5  # the object's own pixels do not
    # and the masked template still finds the object where it is
    f, xy, _ = masked.rescue(with_obj, [1], [[45.0, 45.0]])
    assert f[0]
    np.testing.assert_allclose(xy[0], box[0], atol=0.01)


def test_bad_parameters_are_value_errors() -> None:
    with pytest.raises(ValueError, match="min_score"):
        TemplateBank(min_score=1.5)
    with pytest.raises(ValueError, match="gate_radius"):
        TemplateBank(gate_radius=-1)
    with pytest.raises(ValueError, match="min_travel"):
        TemplateBank(min_travel=-1)
    with pytest.raises(ValueError, match="max_drift"):
        TemplateBank(max_drift=-1)
    with pytest.raises(ValueError, match="min_fill"):
        TemplateBank(min_fill=2)
    with pytest.raises(ValueError, match="one row per track"):
        TemplateBank().observe(_frame(None), [1, 2], [[1, 1]], [[1, 1]])


# --- with the real tracker and disturbance map -----------------------------------------------


def _stop_and_go(n: int, stop: int, go: int, enter: int = 15):
    """Empty road until ``enter``; then a vehicle driving right at 2 px/frame, standing still
    from frame ``stop`` to ``go``."""
    for k in range(n):
        kk = min(k, stop) if k < go else stop + (k - go)
        tl = (10 + 2 * (kk - enter), 50) if k >= enter else None
        yield k, _frame(tl, seed=100 + k), tl


def _run(with_templates: bool, n: int = 200, stop: int = 45, go: int = 185):
    from mvtrack import tracking
    from mvtrack.detection import DisturbanceMap

    tracker = tracking.Tracker(tracking.preset("paper1", fps=30))
    dm = DisturbanceMap()
    rescuer = TemplateRescuer(TemplateBank(), tracker, detector=dm) if with_templates else None
    rows = []
    for _, frame, _ in _stop_and_go(n, stop, go):
        dets = dm(frame)
        rescue = rescuer.callback(frame) if rescuer else None
        out = tracker.step(dets, rescue=rescue)
        if rescuer:
            rescuer.observe(frame, dets, out)
        rows.append(out)
    return rows, rescuer


def _vehicle_track(rows, k: int, xy: np.ndarray) -> int:
    """Public ID of the track nearest to ``xy`` in frame ``k``."""
    r = rows[k]
    return int(r.track_id[np.argmin(np.hypot(*(r.filtered_xy - xy).T))])


STOP_XY = _centre((10 + 2 * (45 - 15), 50))


def test_a_vehicle_that_stops_keeps_its_track_in_state_stopped() -> None:
    from mvtrack.types import TrackState

    rows, rescuer = _run(True)
    uids = rescuer.tracker.tracks.uid
    assert uids.size and (rescuer.radii(uids) == pytest.approx(20.0))  # paper 1's circle
    tid = _vehicle_track(rows, 45, STOP_XY)
    states = []
    for r in rows:
        sel = r.track_id == tid
        states.append(int(r.state[sel][0]) if sel.any() else -1)
    states = np.array(states)
    # alive from the stop until it drives off again (frame 185) and after
    assert (states[45:] >= 0).all(), "the track was lost while the vehicle stood still"
    # after the blob faded (~70 frames after the stop) the track is held by template matching
    assert (states[130:185] == TrackState.STOPPED).all()
    # the held position stays put, at the place of the last (fading, partial) blob, which is
    # on the vehicle
    held = np.array([r.measured_xy[r.track_id == tid][0] for r in rows[130:185]])
    assert np.ptp(held, axis=0).max() < 0.5
    assert np.all(np.abs(held - STOP_XY) <= [VW / 2, VH / 2])
    # when it moves again it is confirmed by detections again, same ID
    assert (states[-5:] == TrackState.CONFIRMED).all()


def test_without_templates_the_stopped_vehicle_track_ends() -> None:
    rows, _ = _run(False, n=150)
    tid = _vehicle_track(rows, 45, STOP_XY)
    assert not any((r.track_id == tid).any() for r in rows[130:150])


def _tracked(config, misses: int = 0, n: int = 10):
    """A tracker that followed two boxes (18×12 and 36×24) for ``n`` frames, then missed
    them ``misses`` times."""
    from mvtrack import tracking
    from mvtrack.types import Detections

    tracker = tracking.Tracker(config)
    for k in range(n + misses):
        xy = [[30.0 + 2 * k, 40.0], [100.0 - k, 80.0]] if k < n else np.zeros((0, 2))
        tracker.step(Detections(k, xy, [[18.0, 12.0], [36.0, 24.0]][: len(xy)]))
    return tracker


def test_search_radius_is_each_tracks_gate() -> None:
    """The search radius of a track is the farthest point of its gate region from the
    centre: the radius of a Euclidean circle; for the default's innovation gate
    ``sqrt(r² λ_max(S))``, wider for the larger box and growing while a track is missed."""
    from mvtrack import tracking

    tracker = _tracked(tracking.paper1(fps=30, gate_px=10.0))
    uids = tracker.tracks.uid
    np.testing.assert_allclose(search_radii(tracker, uids, 20.0), 10.0)
    assert TemplateRescuer(TemplateBank(), tracker).radii(uids) == pytest.approx(10.0)
    assert TemplateRescuer(TemplateBank(), tracker, gate_radius=15).radii(uids) == \
        pytest.approx(15.0)
    assert search_radii(None, uids, 20.0) == pytest.approx(20.0)  # no tracker: the default
    assert search_radii(tracker, [999], 20.0) == pytest.approx(20.0)  # no such track

    seen = _tracked(tracking.TrackerConfig(fps=30.0))
    g = seen.gates()
    major = np.sqrt(g.r2 * np.linalg.eigvalsh(g.shape)[:, -1])  # λ_max, apart from the code
    radii = search_radii(seen, g.uid[::-1], 20.0)
    np.testing.assert_allclose(radii, major[::-1], rtol=1e-9)
    small, large = search_radii(seen, g.uid, 20.0)
    assert 1.5 < large / small < 2.5  # the box twice as large: about twice the radius
    missed = _tracked(tracking.TrackerConfig(fps=30.0), misses=3)
    assert (search_radii(missed, missed.tracks.uid, 20.0) > radii[::-1]).all()
    # the Euclidean gate without a gate is in box sizes: sqrt(9.21 s²) times the longer side
    # of the box (18 × 12 and 36 × 24 px), whatever the track's misses
    from mvtrack.association.gate import euclidean_box_variance

    config = tracking.TrackerConfig(fps=30.0, distance="euclidean")
    s2 = euclidean_box_variance(config.measurement_noise, config.velocity_prior,
                                config.accel_noise, 30.0)
    for m in (0, 3):
        euc = _tracked(config, misses=m)
        np.testing.assert_allclose(search_radii(euc, euc.tracks.uid, 20.0),
                                   np.sqrt(9.21 * s2) * np.array([18.0, 36.0]), rtol=1e-9)
    # the IoU gate is no region about the prediction: the bank's own radius
    iou = _tracked(tracking.TrackerConfig(fps=30.0, distance="iou"))
    assert search_radii(iou, iou.tracks.uid, 20.0) == pytest.approx(20.0)


def test_search_reads_the_gates_once_per_state_of_the_tracker() -> None:
    """The searches before a tracker's step and inside it (the stopped vehicles' pieces, then
    the rescue callback) read its gates once; after the step they are read anew, and the
    radii are those of the tracker's new gates."""
    from mvtrack import tracking
    from mvtrack.types import Detections

    tracker = _tracked(tracking.TrackerConfig(fps=30.0))
    calls = []
    gates = tracker.gates

    def counted():
        calls.append(1)
        return gates()

    tracker.gates = counted
    rescuer = TemplateRescuer(TemplateBank(), tracker)
    uids = tracker.tracks.uid
    xy = np.array([[50.0, 40.0], [90.0, 80.0]])
    wh = np.array([[18.0, 12.0], [36.0, 24.0]])
    frame = np.zeros((120, 160, 3), np.uint8)
    rescuer.search(frame)(uids, xy, wh)
    rescuer.search(frame)(uids, xy, wh)
    rescuer.callback(frame)(uids, xy, wh)
    assert len(calls) == 1
    before = rescuer.radii(uids)
    tracker.step(Detections(10, np.zeros((0, 2)), np.zeros((0, 2))))  # both missed
    rescuer.search(frame)(uids, xy, wh)
    assert len(calls) == 2
    after = rescuer.radii(uids)
    np.testing.assert_allclose(after, search_radii(tracker, uids, 20.0))
    assert (after > before).all()  # a missed track's gate opens


@pytest.mark.parametrize(("th", "tw"), [(10, 18), (30, 20), (64, 40)])
def test_gate_ncc_equals_opencv_masked_ccoeff_normed(th: int, tw: int) -> None:
    """Over the whole window (an unbounded gate) the masked NCC is OpenCV's
    ``TM_CCOEFF_NORMED`` with the mask; in a circular gate, the placements outside it are
    left out and the best is the best inside (the plain function the same)."""
    import cv2

    from mvtrack.detection.ncc import Template, gate_ncc

    rng = np.random.default_rng(th)
    win = cv2.GaussianBlur(rng.integers(0, 256, (th + 41, 2 * tw + 41), dtype=np.uint8), (5, 5),
                           0)
    patch = win[7 : 7 + th, 11 : 11 + tw].copy()
    mask = np.zeros_like(patch)
    mask[th // 4 :, tw // 5 :] = 255
    win[:, -(tw + 3) :] = 77  # a flat strip: flat placements where the mask sees only it
    t = Template(patch, mask, (0.0, 0.0), 0)
    ref = cv2.matchTemplate(win, patch, cv2.TM_CCOEFF_NORMED, mask=mask)
    out = np.empty(ref.shape)
    best, i, c = gate_ncc(win, t.rows, t.cols, t.tz, t.var_t, 0.0, 0.0, np.inf, out)
    flat = ~np.isfinite(ref)  # OpenCV: NaN
    assert flat.any() and np.array_equal(out == -2, flat)
    np.testing.assert_allclose(out[~flat], ref[~flat], atol=2e-5)
    assert (i, c) == (7, 11) and best == pytest.approx(1.0)
    # a gate of radius 5 about placement (20, 25): the best inside it, nothing outside
    for fn in (gate_ncc, gate_ncc.py_func):
        gated = np.empty(ref.shape)
        best, i, c = fn(win, t.rows, t.cols, t.tz, t.var_t, -25.0, -20.0, 25.0, gated)
        yy, xx = np.mgrid[: ref.shape[0], : ref.shape[1]]
        inside = (xx - 25.0) ** 2 + (yy - 20.0) ** 2 <= 25.0
        assert np.isneginf(gated[~inside]).all()
        np.testing.assert_allclose(gated[inside], out[inside], atol=1e-12)
        k = np.flatnonzero(inside.ravel())[np.argmax(out.ravel()[inside.ravel()])]
        assert (i, c) == divmod(int(k), ref.shape[1]) and best == out.ravel()[k]
    # no placement inside the gate
    assert gate_ncc(win, t.rows, t.cols, t.tz, t.var_t, 1e3, 1e3, 1.0, out)[2] == -1


def test_the_stopped_vehicle_guard_searches_max_shift_without_reading_the_gates() -> None:
    """The guard searches around where a vehicle was last seen and refuses matches beyond
    ``max_shift``: its search radius is ``max_shift`` for every track, whether the tracker's
    gate is wider or narrower, and the gates (a prediction of every track) are not computed."""
    from mvtrack import tracking
    from mvtrack.config import RunSettings
    from mvtrack.video import build_rescuer

    for gate_px in (2.0, 20.0):
        tracker = _tracked(tracking.paper1(fps=30, gate_px=gate_px))
        uids = tracker.tracks.uid
        assert TemplateRescuer(TemplateBank(), tracker).radii(uids) == pytest.approx(gate_px)
        guard = build_rescuer(RunSettings(template_params={"max_shift": 5.0}), tracker)

        def no_gates() -> None:
            raise AssertionError("the gates were read")

        tracker.gates = no_gates
        assert guard.inner.radii(uids) == pytest.approx(5.0)
    # a vehicle 6 px from the search centre is found with a 20 px radius, not with 4 px
    tl = (50, 40)
    bank = _bank_with_vehicle(tl)
    frame = _frame(tl, seed=2)
    off = [_centre(tl) + np.array([6.0, 0.0])]
    assert bank.rescue(frame, [7], off, gate_radius=20)[0][0]
    assert not bank.rescue(frame, [7], off, gate_radius=4)[0][0]


def test_observe_maps_rows_by_row_uids_or_by_public_id_alike() -> None:
    """The rescuer stores a frame's detected boxes under the tracker's uids, whether it reads
    them from ``tracker.row_uids`` or looks them up by public ID."""
    from types import SimpleNamespace

    from mvtrack import tracking
    from mvtrack.detection import DisturbanceMap

    tracker = tracking.Tracker(tracking.preset("paper1", fps=30))
    dm = DisturbanceMap()
    by_row = TemplateRescuer(TemplateBank(), tracker, detector=dm)
    shim = SimpleNamespace(tracks=None)  # no row_uids: lookup by track_id
    by_id = TemplateRescuer(TemplateBank(), shim, detector=dm)
    for _, frame, _ in _stop_and_go(60, 45, 100):
        dets = dm(frame)
        out = tracker.step(dets, rescue=by_row.callback(frame))
        shim.tracks = tracker.tracks
        by_row.observe(frame, dets, out)
        by_id.observe(frame, dets, out)
    assert len(by_row.bank) > 0
    np.testing.assert_array_equal(by_row.bank.uids, by_id.bank.uids)
    np.testing.assert_array_equal(by_row.bank.eligible, by_id.bank.eligible)
    np.testing.assert_array_equal(by_row.bank._f, by_id.bank._f)


def test_build_rescuer_gives_the_bank_the_detectors_mask_and_min_pixels() -> None:
    from mvtrack.config import RunSettings
    from mvtrack.detection import DisturbanceMap
    from mvtrack.video import build_rescuer, build_tracker

    tracker = build_tracker(RunSettings(), 30.0)
    dm = DisturbanceMap(min_area=40)
    rescuer = build_rescuer(RunSettings(), tracker, dm)
    assert rescuer.inner.detector is dm
    assert rescuer.inner.bank.min_pixels == 20  # half the detector's min_area
    assert rescuer.max_shift == 4.0
    own = build_rescuer(RunSettings(template_params={"min_pixels": 70}), tracker, dm)
    assert own.inner.bank.min_pixels == 70
    # the travel guard is the bank's (min_travel in box lengths, min_travel_px)
    bank = build_rescuer(
        RunSettings(template_params={"min_travel": 2.0, "min_travel_px": 15}), tracker
    ).inner.bank
    assert (bank.min_travel, bank.min_travel_px) == (2.0, 15.0)


def test_per_track_eligibility_check_agrees_with_the_array_form() -> None:
    """The search checks the travel guard track by track in plain floats; it must agree with
    the array form behind ``eligible`` on every row."""
    rng = np.random.default_rng(11)
    for min_travel, min_travel_px, min_hits in [(1.0, 10.0, 5), (0.0, 3.0, 0), (2.0, 0.0, 2)]:
        bank = TemplateBank(min_travel=min_travel, min_travel_px=min_travel_px, min_hits=min_hits)
        f = bank._empty_rows(400)
        f[:, 0:11] = rng.uniform(0, 40, (400, 11))
        f[:, 12] = rng.integers(0, 9, 400)
        f[:50, 6:8] = f[:50, 9:11]  # no travel at all
        want = bank._eligible_rows(f)
        assert 0 < want.sum() < 400
        assert [bank._eligible_row(row) for row in f.tolist()] == want.tolist()


def test_search_prefilter_skips_leaving_drifting_and_unknown_tracks() -> None:
    """The missed tracks that are unknown, predicted with their box outside the image, or
    (with ``max_drift``) predicted far from their last place get no search (NaN score)."""
    tl = (50, 40)
    bank = TemplateBank(min_travel=0, min_travel_px=0, min_hits=0, max_drift=None, smooth=0)
    other = [130.0, 100.0]
    bank.observe(_frame(tl, seed=1), [7, 8], [_centre(tl), other], [[VW, VH], [VW, VH]])
    frame = _frame(tl, seed=2)
    uids = [7, 9, 8]  # 9 is unknown; 8 is predicted with its box past the right border
    pred = [_centre(tl) + 1.0, _centre(tl), [155.0, 100.0]]
    found, xy, score = bank.rescue(frame, uids, pred)
    assert found.tolist() == [True, False, False]
    assert np.isfinite(score[0]) and np.isnan(score[1:]).all()
    np.testing.assert_allclose(xy[0], _centre(tl), atol=0.01)
    assert np.isnan(xy[1:]).all()
    found, _, score = bank.rescue(frame, [8], [[128.0, 100.0]])  # inside: searched
    assert np.isfinite(score[0])
    found, _, score = bank.rescue(frame, [7], [[np.nan, np.nan]])  # no prediction
    assert not found[0] and np.isnan(score[0])
    bank.max_drift = 5.0
    found, _, score = bank.rescue(frame, [7, 8], [_centre(tl) + 1.0, [121.0, 100.0]])
    assert found.tolist() == [True, False] and np.isnan(score[1])  # 8 drifted 9 px
