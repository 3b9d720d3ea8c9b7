"""Detection front ends: disturbance map, frame differencing, MOG2 and the blob stage."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from mvtrack.detection import (
    DETECTORS,
    MOG2,
    BlobExtractor,
    DisturbanceMap,
    FrameDifference,
    blobs_from_mask,
    make_detector,
)

H, W = 120, 160
SIDE = 10


def _scene(n: int, path, seed: int = 0, bg: int = 100, fg: int = 200, sigma: float = 3.0):
    """Grey noise frames with a bright SIDE×SIDE square whose top-left is ``path(k)`` (or None)."""
    rng = np.random.default_rng(seed)
    for k in range(n):
        img = np.clip(rng.normal(bg, sigma, (H, W)), 0, 255).astype(np.uint8)
        tl = path(k)
        if tl is not None:
            x, y = tl
            img[y : y + SIDE, x : x + SIDE] = fg
        yield k, cv2.cvtColor(img, cv2.COLOR_GRAY2BGR), tl


def _moving(k: int, start: int = 30, x0: int = 20, y0: int = 50, vx: int = 2):
    return None if k < start else (x0 + vx * (k - start), y0)


def test_disturbance_map_finds_one_moving_square_with_its_centroid_and_box() -> None:
    dm = DisturbanceMap()
    checked = 0
    for k, frame, tl in _scene(70, _moving):
        dets = dm(frame)
        assert dets.frame == k
        if k < 35:  # background settling, square just appeared
            continue
        assert len(dets) == 1, (k, dets.xy)
        x, y = tl
        # pixel centres on integers: the square covers x .. x+9, centre x + 4.5
        np.testing.assert_allclose(dets.xy[0], [x + 4.5, y + 4.5], atol=1.0)
        np.testing.assert_array_equal(dets.wh[0], [SIDE, SIDE])
        assert dets.area[0] == SIDE * SIDE
        np.testing.assert_allclose(dets.tlwh[0], [x - 0.5, y - 0.5, SIDE, SIDE], atol=1.0)
        checked += 1
    assert checked == 35


def test_background_follows_the_beta_rule_exactly_on_a_hand_computed_2x2_example() -> None:
    # T = 25, β_min = 0.4 so that β_1 = max(1/2, 0.4) = 0.5 and β_2 = β_3 = 0.4 (the floor)
    dm = DisturbanceMap(threshold=25, beta_min=0.4, open_size=0, min_area=1)
    frames = [
        np.array([[0, 100], [200, 50]], np.uint8),
        np.array([[100, 100], [100, 60]], np.uint8),
        np.array([[80, 130], [150, 20]], np.uint8),
        np.array([[90, 136], [120, 67]], np.uint8),
    ]
    backgrounds = [
        [[0, 100], [200, 50]],  # B_0 = I_0
        [[50, 100], [150, 55]],  # B_1 = 0.5 B_0 + 0.5 I_1
        [[62, 112], [150, 41]],  # B_2 = 0.6 B_1 + 0.4 I_2
        [[73.2, 121.6], [138, 51.4]],  # B_3 = 0.6 B_2 + 0.4 I_3
    ]
    masks = [
        None,
        [[1, 0], [1, 0]],  # D_1 = [[100, 0], [-100, 10]]
        [[1, 1], [0, 1]],  # D_2 = [[30, 30], [0, -35]]
        [[1, 0], [1, 1]],  # D_3 = [[28, 24], [-30, 26]]
    ]
    for k, (img, b, m) in enumerate(zip(frames, backgrounds, masks, strict=True)):
        dets = dm(img)
        np.testing.assert_allclose(dm.background, b, atol=1e-4)
        if m is None:
            assert dm.raw_mask is None and len(dets) == 0
        else:
            np.testing.assert_array_equal(dm.raw_mask > 0, np.array(m, bool), err_msg=f"k={k}")
    assert [dm.beta(k) for k in (1, 2, 3)] == [0.5, 0.4, 0.4]


def test_stopped_square_fades_into_the_background_after_about_the_memory_length() -> None:
    stop = 60

    def path(k: int):
        return None if k < 20 else (20 + 2 * (min(k, stop) - 20), 50)

    dm = DisturbanceMap()
    seen = []
    for _, frame, _ in _scene(stop + 120, path):
        seen.append(len(dm(frame)))
    # From the stop, 200 − B_k shrinks by (1 − 0.02) per frame from ≲ 100 grey levels, so the
    # contrast drops under T = 25 after at most ln(100/25)/−ln(0.98) ≈ 69 frames.
    bound = math.log(100 / 25) / -math.log(0.98)
    after = np.array(seen[stop:])
    assert (after[:30] == 1).all()  # still seen well inside the memory
    gone = int(np.argmax(after == 0))
    assert after[gone:].sum() == 0  # once gone, it stays gone
    assert 30 < gone <= bound + 2


def test_frame_differencing_detects_a_moving_square_near_its_position() -> None:
    fd = make_detector("frame-diff")
    assert isinstance(fd, FrameDifference)
    for k, frame, tl in _scene(40, lambda k: (20 + 3 * k, 50)):
        dets = fd(frame)
        if k == 0:
            assert len(dets) == 0
            continue
        assert len(dets) >= 1
        x, y = tl
        # every blob lies within the union of the previous and the current square
        x1y1 = dets.xy - (dets.wh - 1) / 2
        assert (x1y1[:, 0] >= x - 3 - 1).all() and (
            x1y1[:, 0] + dets.wh[:, 0] <= x + SIDE + 1
        ).all()
        assert (np.abs(dets.xy[:, 1] - (y + 4.5)) <= 1).all()


def test_mog2_detects_a_moving_square_after_learning_the_background() -> None:
    mog = make_detector("mog2")
    assert isinstance(mog, MOG2)
    hits = 0
    for k, frame, tl in _scene(80, _moving):
        dets = mog(frame)
        if k >= 40:
            x, y = tl
            d = np.hypot(*(dets.xy - [x + 4.5, y + 4.5]).T)
            hits += bool(len(dets)) and d.min() <= 2.0
    assert hits == 40


def test_knn_detects_a_moving_square_and_not_the_static_background() -> None:
    from mvtrack.detection import KNN

    knn = make_detector("knn", min_area=5)
    assert isinstance(knn, KNN) and knn.blobs.min_area == 5
    hits = false = 0
    for k, frame, tl in _scene(80, _moving):
        dets = knn(frame)
        if k >= 40:
            x, y = tl
            d = np.hypot(*(dets.xy - [x + 4.5, y + 4.5]).T)
            hits += bool(len(dets)) and d.min() <= 2.0
            false += int((d > 2.0 * SIDE).sum()) if len(dets) else 0
    assert hits == 40 and false == 0, (hits, false)
    with pytest.raises(ValueError, match=r"^detector 'knn': .*dist2_threshold"):
        make_detector("knn", dist2_threshold=0)
    with pytest.raises(ValueError, match=r"^detector 'disturbance-map': hold must be"):
        make_detector("disturbance-map", hold=-5)


def test_reset_forgets_the_background() -> None:
    dm = DisturbanceMap()
    frames = list(_scene(40, _moving))
    first = [len(dm(f)) for _, f, _ in frames]
    dm.reset()
    assert dm.background is None and dm.frames_seen == 0
    second = [len(dm(f)) for _, f, _ in frames]
    assert first == second


def test_explicit_frame_index_is_stored_in_the_detections() -> None:
    dm = DisturbanceMap()
    for k, frame, _ in _scene(3, _moving):
        assert dm(frame, index=100 + k).frame == 100 + k


def test_warmup_suppresses_the_first_frames() -> None:
    dm = DisturbanceMap(warmup=40)
    counts = [len(dm(f)) for _, f, _ in _scene(45, _moving)]
    assert counts[:40] == [0] * 40 and counts[40:] == [1] * 5


# --- blob stage ------------------------------------------------------------------------------


def _mask_with_blobs() -> np.ndarray:
    m = np.zeros((60, 80), np.uint8)
    m[5:7, 5:10] = 255  # area 10
    m[20:26, 20:25] = 255  # area 30
    m[40:50, 40:50] = 255  # area 100
    return m


def test_area_filters_keep_blobs_between_min_and_max() -> None:
    m = _mask_with_blobs()
    assert sorted(blobs_from_mask(m, 0, min_area=0).area) == [10, 30, 100]
    assert sorted(blobs_from_mask(m, 0).area) == [30, 100]  # default min 20 px
    kept = blobs_from_mask(m, 7, min_area=20, max_area=50)
    assert kept.frame == 7 and list(kept.area) == [30]
    np.testing.assert_allclose(kept.xy, [[22.0, 22.5]])
    np.testing.assert_array_equal(kept.wh, [[5, 6]])


def test_centroid_and_box_centre_differ_for_an_l_shaped_blob() -> None:
    m = np.zeros((30, 30), np.uint8)
    m[10:20, 10:12] = 255  # vertical bar, 20 px
    m[18:20, 12:20] = 255  # foot, 16 px
    (c,) = blobs_from_mask(m, 0, min_area=1).xy
    (b,) = blobs_from_mask(m, 0, min_area=1, center="box").xy
    np.testing.assert_allclose(b, [14.5, 14.5])
    ys, xs = np.nonzero(m)
    np.testing.assert_allclose(c, [xs.mean(), ys.mean()])


def test_eight_connectivity_joins_diagonal_pixels_and_four_does_not() -> None:
    m = np.zeros((10, 10), np.uint8)
    m[2:4, 2:4] = 255
    m[4:6, 4:6] = 255  # touches only at a corner
    assert len(blobs_from_mask(m, 0, min_area=1, connectivity=8)) == 1
    assert len(blobs_from_mask(m, 0, min_area=1, connectivity=4)) == 2


def test_opening_removes_speckle_and_closing_merges_fragments() -> None:
    m = np.zeros((60, 60), np.uint8)
    rng = np.random.default_rng(1)
    ys, xs = rng.integers(0, 60, (2, 30))
    m[ys, xs] = 255  # isolated noise pixels
    m[10:30, 10:20] = 255
    m[32:45, 10:20] = 255  # the same object, split by a 2-px gap
    m_clean = m.copy()
    assert len(BlobExtractor(min_area=1, open_size=0)(m, 0)) > 2
    two = BlobExtractor(min_area=20)(m_clean, 0)
    assert len(two) == 2
    one = BlobExtractor(min_area=20, close_size=5)(m_clean, 0)
    assert len(one) == 1
    np.testing.assert_array_equal(one.wh[0], [10, 35])


def test_factory_rejects_unknown_names_and_parameters() -> None:
    with pytest.raises(ValueError, match="disturbance-map, frame-diff, mog2"):
        make_detector("optical-flow")
    with pytest.raises(ValueError, match="tresh"):
        make_detector("disturbance-map", tresh=3)
    assert set(DETECTORS) == {"disturbance-map", "frame-diff", "mog2", "knn", "hog", "scene",
                              "road-users"}
    dm = make_detector("disturbance-map", threshold=30, beta_min=0.05, min_area=5, close_size=7)
    assert (dm.threshold, dm.beta_min, dm.blobs.min_area, dm.blobs.close_size) == (30, 0.05, 5, 7)


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"threshold": -1}, "threshold"),
        ({"beta_min": 0}, "beta_min"),
        ({"min_area": -5}, "min_area"),
        ({"min_area": 50, "max_area": 10}, "max_area"),
        ({"connectivity": 6}, "connectivity"),
        ({"center": "middle"}, "center"),
        ({"warmup": -1}, "warmup"),
    ],
)
def test_bad_parameters_name_themselves(kwargs: dict, word: str) -> None:
    with pytest.raises(ValueError, match=word):
        DisturbanceMap(**kwargs)


def test_non_uint8_frames_are_rejected() -> None:
    with pytest.raises(ValueError, match="uint8"):
        DisturbanceMap()(np.zeros((4, 4), np.float32))


def test_disturbance_map_finds_a_plausible_number_of_pedestrians_in_vtest(vtest_path: Path) -> None:
    from mvtrack.io.video import open_source

    dm = DisturbanceMap()
    counts, areas = [], []
    with open_source(vtest_path) as src:
        for k, frame in itertools.islice(src, 300):
            dets = dm(frame)
            if k >= 60:  # background settled
                counts.append(len(dets))
                areas.extend(dets.area)
    assert 2 <= np.median(counts) <= 40
    assert min(areas) >= 20
    # pedestrians are a few hundred to a few thousand pixels at this scale
    assert 100 <= np.percentile(areas, 90) <= 20000


def test_frame_differencing_splits_a_uniform_object_the_disturbance_map_keeps_whole() -> None:
    # paper 1's reason to reject frame differencing: a uniform object's interior cancels, so
    # one 20×20 square moving 4 px/frame gives two edge strips; the disturbance map one blob
    def big(k: int):
        return None if k < 30 else (10 + 4 * (k - 30), 40)

    rng = np.random.default_rng(5)
    fd, dm = FrameDifference(), DisturbanceMap()
    for k in range(50):
        img = np.clip(rng.normal(100, 3, (H, W)), 0, 255).astype(np.uint8)
        tl = big(k)
        if tl is not None:
            img[tl[1] : tl[1] + 20, tl[0] : tl[0] + 20] = 200
        f, d = fd(img), dm(img)
    assert len(f) == 2
    np.testing.assert_array_equal(np.sort(f.wh[:, 0]), [4, 4])
    assert len(d) == 1 and tuple(d.wh[0]) == (20, 20)


def test_more_blobs_than_16_bit_labels_hold_are_all_found() -> None:
    """Labelling uses 16-bit labels and falls back to 32-bit ones beyond 65535 blobs."""
    from mvtrack.detection.blobs import blobs_from_mask

    m = np.zeros((600, 600), np.uint8)
    m[::2, ::2] = 255  # 90 000 isolated pixels, each its own 8-connected blob
    dets = blobs_from_mask(m, 0, min_area=1)
    assert len(dets) == 300 * 300
    np.testing.assert_array_equal(np.sort(dets.xy[:, 0])[::300], np.arange(0, 600, 2))
    small = blobs_from_mask(m[:20, :20], 0, min_area=1)
    assert len(small) == 100


@pytest.mark.parametrize("close_size", [3, 6, 7, 9])
def test_closing_around_the_foreground_equals_closing_the_whole_mask(close_size: int) -> None:
    """The blob stage closes only the foreground's bounding rectangle plus a margin; the
    result must be the closing of the whole image, also for blobs touching the border."""
    rng = np.random.default_rng(close_size)
    rect = cv2.getStructuringElement(cv2.MORPH_RECT, (3, 3))
    ellipse = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_size, close_size))
    for _ in range(60):
        h, w = rng.integers(20, 100, 2)
        m = np.zeros((h, w), np.uint8)
        for _ in range(rng.integers(1, 6)):
            y, x = rng.integers(0, h), rng.integers(0, w)
            dh, dw = rng.integers(1, 15, 2)
            m[y : y + dh, x : x + dw] = 255
        m[rng.random((h, w)) < 0.02] = 255
        ours = BlobExtractor(open_size=3, close_size=close_size).clean(m)
        ref = cv2.morphologyEx(cv2.morphologyEx(m, cv2.MORPH_OPEN, rect), cv2.MORPH_CLOSE, ellipse)
        np.testing.assert_array_equal(ours, ref)


def test_blobs_labelled_band_by_band_equal_those_of_the_whole_mask() -> None:
    """Rows without foreground split the mask into bands labelled one by one; the blobs
    (centroid, box, area) must be those of labelling the whole mask."""
    from mvtrack.detection.blobs import blobs_from_mask

    rng = np.random.default_rng(5)
    for trial in range(40):
        m = np.zeros((90, 120), np.uint8)
        for _ in range(rng.integers(1, 9)):  # blobs in a few separate bands, some sharing rows
            y, x = rng.integers(0, 85), rng.integers(0, 110)
            m[y : y + rng.integers(1, 6), x : x + rng.integers(1, 12)] = 255
        if trial % 2:
            m[rng.random(m.shape) < 0.01] = 255
        n, _, stats, cents = cv2.connectedComponentsWithStats(m, connectivity=8)
        ref = np.concatenate([cents[1:], stats[1:, [2, 3, 4]]], axis=1)
        for center in ("centroid", "box"):
            dets = blobs_from_mask(m, 0, min_area=1, center=center)
            assert len(dets) == n - 1
        dets = blobs_from_mask(m, 0, min_area=1)
        ours = np.concatenate([dets.xy, dets.wh, dets.area[:, None]], axis=1)
        np.testing.assert_allclose(ours[np.lexsort(ours.T[::-1])], ref[np.lexsort(ref.T[::-1])])
        kept = blobs_from_mask(m, 0, min_area=4, max_area=20)
        assert len(kept) == int(((stats[1:, 4] >= 4) & (stats[1:, 4] <= 20)).sum())


@pytest.mark.parametrize(("open_size", "close_size"), [(3, 7), (3, 5), (0, 7), (3, 0), (5, 9)])
def test_opening_and_closing_group_by_group_equal_those_of_the_whole_mask(
    open_size: int, close_size: int
) -> None:
    """The blob stage opens and closes only around separate groups of rows of the eroded
    mask; the result must be the opening and closing of the whole image, whether the groups
    lie far apart, just far enough apart or close together, and at the image border."""
    rng = np.random.default_rng(open_size * 10 + close_size)
    extractor = BlobExtractor(open_size=open_size, close_size=close_size)
    for trial in range(60):
        h, w = int(rng.integers(60, 300)), int(rng.integers(20, 120))
        m = np.zeros((h, w), np.uint8)
        y = int(rng.integers(-3, 10))
        while y < h:  # blobs stacked downwards with gaps of 0 to 40 rows
            dh, dw = rng.integers(1, 15, 2)
            x = int(rng.integers(-3, w))
            m[max(y, 0) : y + dh, max(x, 0) : x + dw] = 255
            y += int(dh) + int(rng.integers(0, 40))
        if trial % 2:
            m[rng.random((h, w)) < 0.03] = 255
        ref = m
        if open_size > 1:
            rect = cv2.getStructuringElement(cv2.MORPH_RECT, (open_size, open_size))
            ref = cv2.morphologyEx(ref, cv2.MORPH_OPEN, rect)
        if close_size > 1:
            ellipse = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_size, close_size))
            ref = cv2.morphologyEx(ref, cv2.MORPH_CLOSE, ellipse)
        np.testing.assert_array_equal(extractor.clean(m), ref)


@pytest.mark.parametrize("threshold", [25.0, 25.3, 7.77])
def test_disturbance_mask_is_the_float32_difference_above_the_threshold(threshold: float) -> None:
    """|I_k − B_{k−1}| > T on the float32 background, also for a T that float32 cannot hold
    exactly, as a 0/255 mask; a threshold changed between frames takes effect."""
    rng = np.random.default_rng(3)
    dm = DisturbanceMap(threshold=threshold, open_size=0, min_area=1)
    for k in range(12):
        if k == 8:
            dm.threshold = threshold + 10.0
        img = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
        grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY).astype(np.float32)
        before = None if dm.background is None else dm.background.copy()
        dm(img)
        if before is None:
            continue
        ref = np.abs(grey - before) > np.float32(dm.threshold)
        assert set(np.unique(dm.raw_mask).tolist()) <= {0, 255}
        np.testing.assert_array_equal(dm.raw_mask > 0, ref, err_msg=f"k={k}")
