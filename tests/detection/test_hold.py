"""The disturbance map's ``hold`` (not in paper 1): pixels under the confirmed tracks' predicted
boxes are kept out of the running average, so a vehicle that waits stays foreground and leaves
no ghost when it drives on; after ``hold`` frames in a row they are learnt again (the slow path:
an object that parks is absorbed on purpose)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection import background, make_detector
from mvtrack.detection.background import box_cover, count_held
from mvtrack.tracking import Tracker, TrackerConfig

STAND = (60, 360)  # frames the vehicle stands still (it drives before and after)


def _scene(n: int = 420) -> list[np.ndarray]:
    """A textured road; a bright 16×10 vehicle drives in from the left at 2 px per frame,
    stands at x = 60 … 76 over frames ``STAND``, then drives on to the right."""
    rng = np.random.default_rng(0)
    road = (60 + rng.integers(0, 20, (60, 200))).astype(np.uint8)
    frames = []
    for k in range(n):
        img = road.copy()
        x = -60 + 2 * min(k, STAND[0]) + 3 * max(0, k - STAND[1])
        if -16 < x < 200:
            img[25:35, max(x, 0) : max(x + 16, 0)] = 220
        frames.append(np.dstack([img] * 3))
    return frames


def _run(hold: int) -> tuple[list[bool], list[bool]]:
    """Per frame: is there a blob on the standing place, and one on the vehicle after it left."""
    det = make_detector("disturbance-map", hold=hold, close_size=3, min_area=20.0)
    tracker = Tracker(TrackerConfig(fps=30.0))
    at_place, on_vehicle = [], []
    for k, f in enumerate(_scene()):
        d = det(f)
        det.observe(d, tracker.step(d))
        at_place.append(any(60 <= x <= 76 and 25 <= y <= 35 for x, y in d.xy))
        x = 60 + 3 * max(0, k - STAND[1]) + 8
        on_vehicle.append(any(abs(cx - x) <= 8 for cx, _ in d.xy))
    return at_place, on_vehicle


def test_a_waiting_vehicle_stays_foreground_and_leaves_no_ghost() -> None:
    held, moving = _run(hold=1000)
    paper, moving0 = _run(hold=0)
    a, b = STAND
    assert all(held[a + 5 : b])  # detected through its whole wait
    assert sum(paper[a + 5 : b]) < 0.5 * (b - a)  # paper 1: absorbed within its wait
    after = slice(b + 10, b + 50)  # the vehicle has left its place (≥ 30 px away)
    assert not any(held[after])  # no ghost where it stood
    assert sum(paper[after]) >= 10  # paper 1's ghost
    assert all(moving[b + 10 : b + 40]) and all(moving0[b + 10 : b + 40])  # the vehicle


def test_a_vehicle_held_longer_than_hold_is_absorbed_on_the_slow_path() -> None:
    held, _ = _run(hold=100)
    a, b = STAND
    assert all(held[a + 5 : a + 100])  # held while under ``hold`` frames
    assert not any(held[a + 250 : b])  # then learnt at the usual rate, and gone


def test_hold_off_gives_paper_1s_map_exactly() -> None:
    frames = _scene(200)
    plain = make_detector("disturbance-map", close_size=3, min_area=20.0)
    observed = make_detector("disturbance-map", hold=0, close_size=3, min_area=20.0)
    tracker = Tracker(TrackerConfig(fps=30.0))
    for f in frames:
        d0, d1 = plain(f), observed(f)
        observed.observe(d1, tracker.step(d1))
        np.testing.assert_array_equal(d0.tlwh, d1.tlwh)
    np.testing.assert_array_equal(plain.background, observed.background)


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_box_cover_matches_filling_the_boxes_one_by_one(seed, compiled, monkeypatch) -> None:
    if not compiled:  # the plain function the kernel is compiled from
        monkeypatch.setattr(background, "fill_boxes", background.fill_boxes.py_func)
    rng = np.random.default_rng(seed)
    shape = (37, 53)
    boxes = np.column_stack([rng.uniform(-10, 55, (9, 2)), rng.uniform(0.5, 20, (9, 2))])
    ref = np.zeros(shape, bool)
    for x, y, w, h in boxes:  # the reference: every pixel whose square meets the box
        x0, y0 = max(int(np.floor(x)), 0), max(int(np.floor(y)), 0)
        x1, y1 = max(int(np.ceil(x + w)), 0), max(int(np.ceil(y + h)), 0)
        ref[y0:y1, x0:x1] = True
    np.testing.assert_array_equal(box_cover(boxes, shape), 255 * ref.astype(np.uint8))
    assert not box_cover(np.zeros((0, 4)), shape).any()
    big = np.vstack([boxes, [[-5.0, -5.0, 60.0, 30.0]]])  # most of the image, filled
    ref[:25, :55] = True
    np.testing.assert_array_equal(box_cover(big, shape), 255 * ref.astype(np.uint8))
    many = np.vstack([big, [[-1.0, -1.0, 60.0, 40.0]] * 2])  # over twice: prefix sums
    np.testing.assert_array_equal(box_cover(many, shape), np.full(shape, 255, np.uint8))
    assert not box_cover(np.array([[5.0, 5.0, 0.0, 3.0]]), shape).any()  # empty box


def test_box_cover_gives_its_kernel_contiguous_ends(monkeypatch) -> None:
    """One layout, so numba compiles ``fill_boxes`` once (a strided row would be a second)."""
    kernel, seen = background.fill_boxes, []

    def checked(out, *ends):  # type: ignore[no-untyped-def]
        seen.extend(e.flags.c_contiguous for e in ends)
        return kernel(out, *ends)

    monkeypatch.setattr(background, "fill_boxes", checked)
    box_cover(np.array([[1.0, 2.0, 5.0, 6.0], [10.0, 3.0, 4.0, 4.0]]), (20, 20))
    assert seen == [True] * 4


@pytest.mark.parametrize("bad", [-1, 2.5, True, "60", 65535])
def test_hold_must_be_a_whole_number_of_frames(bad) -> None:
    with pytest.raises(ValueError, match="hold"):
        make_detector("disturbance-map", hold=bad)


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("hold", [0, 2, 70000])
def test_count_held_matches_counting_frame_by_frame(compiled, hold) -> None:
    """Each pixel's count of frames in a row under a box, capped at ``hold + 1`` (and at the
    uint16's range), and the learnt mask (outside, or held over ``hold`` frames), against a
    plain NumPy count over random masks."""
    rng = np.random.default_rng(hold)
    fn = count_held if compiled else count_held.py_func
    held = np.zeros((7, 9), np.uint16)
    ref = np.zeros((7, 9), np.int64)
    for _ in range(6):
        inside = np.where(rng.random((7, 9)) < 0.7, 255, 0).astype(np.uint8)
        learnt = np.full((7, 9), 7, np.uint8)
        fn(inside, held, hold, learnt)
        ref = np.where(inside > 0, np.minimum(ref + 1, min(hold + 1, 65535)), 0)
        np.testing.assert_array_equal(held, ref)
        np.testing.assert_array_equal(learnt, np.where((inside == 0) | (ref > hold), 255, 0))


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_hold_boxes_matches_count_held_of_box_cover(seed, compiled) -> None:
    """The fused kernel against :func:`box_cover` then :func:`count_held` (plain NumPy and
    the kernel checked above), frame after frame; over twice the image's pixels it leaves
    the work to them."""
    fn = background.hold_boxes if compiled else background.hold_boxes.py_func
    rng = np.random.default_rng(seed)
    shape = (23, 31)
    held, ref_held = np.zeros(shape, np.uint16), np.zeros(shape, np.uint16)
    cover = np.empty(shape, np.uint8)
    for _ in range(5):
        n = int(rng.integers(0, 6))
        boxes = np.column_stack([rng.uniform(-8, 33, (n, 2)), rng.uniform(0, 14, (n, 2))])
        learnt, ref = np.empty(shape, np.uint8), np.empty(shape, np.uint8)
        assert fn(np.ascontiguousarray(boxes), cover, held, 2, learnt)
        count_held.py_func(box_cover(boxes, shape), ref_held, 2, ref)
        np.testing.assert_array_equal(held, ref_held)
        np.testing.assert_array_equal(learnt, ref)
    many = np.array([[-1.0, -1.0, 40.0, 30.0]] * 3)
    before = held.copy()
    assert not fn(many, cover, held, 2, learnt)
    np.testing.assert_array_equal(held, before)
