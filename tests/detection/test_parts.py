"""Part segmentation, adjacency, features and matching of paper 3 (SPEC §3.1, §3.3)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection.parts import (
    DetectionZone,
    PartFeatures,
    adjacency,
    bgr_to_hsi,
    circular_kmeans2,
    feature_distance,
    match_parts,
    moving_box,
    moving_region,
    occlusion_degree,
    region_features,
    segment_parts,
)
from mvtrack.sim.occlusion import render_occlusion_scene


@pytest.fixture(scope="module")
def scene():
    return render_occlusion_scene(n_frames=60, seed=1)


def _hue_err(a: float, b: float) -> float:
    d = abs(a - b) % 360
    return min(d, 360 - d)


def test_hsi_of_primary_and_grey_pixels() -> None:
    px = np.array([[[0, 0, 255], [0, 255, 0], [255, 0, 0], [128, 128, 128], [0, 128, 255]]])
    hue, sat, inten = bgr_to_hsi(px.astype(np.uint8))
    np.testing.assert_allclose(hue[0, :3], [0.0, 120.0, 240.0], atol=1e-9)
    np.testing.assert_allclose(sat[0, :3], 1.0)
    assert sat[0, 3] == pytest.approx(0.0) and inten[0, 3] == pytest.approx(128.0)
    # orange (R=255, G=128, B=0): θ = arccos(½(127+255)/√(127²+255·128))
    theta = np.degrees(np.arccos(0.5 * (127 + 255) / np.sqrt(127**2 + 255 * 128)))
    assert hue[0, 4] == pytest.approx(theta)


def test_circular_kmeans_splits_across_the_zero_hue_wrap() -> None:
    rng = np.random.default_rng(0)
    reds = (rng.normal(0, 5, 300)) % 360  # around 0°, on both sides of the wrap
    blues = rng.normal(200, 5, 200)
    centres, second = circular_kmeans2(np.concatenate([reds, blues]))
    got = sorted(centres, key=lambda c: _hue_err(c, 0))
    assert _hue_err(got[0], 0) < 2 and _hue_err(got[1], 200) < 2
    assert second[:300].all() != second[300:].all()
    assert len(set(second[:300].tolist())) == 1 and len(set(second[300:].tolist())) == 1


def test_x9_walker_segments_into_three_hues_with_chain_adjacency(scene) -> None:
    hue, sat, _ = bgr_to_hsi(scene.frames[10])
    x0, y0, x1, y1 = 20, 80, 80, 200
    mask = np.zeros(hue.shape, bool)
    mask[y0:y1, x0:x1] = True
    labels, hues = segment_parts(hue, sat, mask)
    assert len(hues) == 3
    for got, want in zip(hues, (30, 210, 120), strict=True):  # ordered top to bottom
        assert _hue_err(got, want) < 5
    for k in (1, 2, 3):  # every true part pixel carries its part's label
        assert np.array_equal(labels == k, scene.labels[10] == k)
    assert adjacency(labels).tolist() == [[1, 2], [2, 3]]


def test_small_and_grey_regions_are_dropped() -> None:
    hue = np.full((40, 40), 100.0)
    sat = np.zeros((40, 40))
    sat[5:25, 5:25] = 0.8  # 400 px of hue 100
    hue[30:34, 30:34], sat[30:34, 30:34] = 300.0, 0.8  # 16 px: under 30 px
    labels, hues = segment_parts(hue, sat, np.ones((40, 40), bool))
    assert len(hues) == 1 and _hue_err(hues[0], 100) < 1e-6
    assert (labels == 1).sum() == 400 and labels[31, 31] == 0


def test_adjacency_needs_three_shared_boundary_pixels() -> None:
    lab = np.zeros((10, 10), np.int32)
    lab[0:5, 0:5] = 1
    lab[5:10, 0:5] = 2  # shares a 5-pixel edge with 1
    lab[5:6, 5:6] = 3  # touches 2 at one pixel only
    lab[0:5, 7:10] = 4  # a 2-px seam from part 1 (columns 5, 6): bridged by gap=3
    assert adjacency(lab, min_shared=3, gap=1).tolist() == [[1, 2]]
    assert adjacency(lab, min_shared=3, gap=3).tolist() == [[1, 2], [1, 4]]


def test_moving_region_fills_the_interior_of_a_moving_box() -> None:
    a = np.full((60, 80), 100, np.uint8)
    b = a.copy()
    a[20:40, 10:30] = 200
    b[20:40, 14:34] = 200  # moved 4 px right; only the leading/trailing strips differ
    b[5, 70] = 0  # one-pixel noise
    region = moving_region(a, b, threshold=20, close_size=21)
    assert region[30, 20] and region[30, 12] and region[30, 32]
    assert not region[5, 70] and not region[50, 5]


def test_walker_is_picked_up_in_the_door_zone(scene) -> None:
    zone = DetectionZone(*scene.door)
    box = moving_box(scene.frames[0], scene.frames[1], zone)
    true = scene.boxes[:2]  # (2 frames, 3 parts, 4)
    want = [true[..., 0].min(), true[..., 1].min(), true[..., 2].max(), true[..., 3].max()]
    np.testing.assert_allclose(box, want, atol=3.0)
    # far from the door nothing is picked up, though the walker moves there later
    far = DetectionZone(200, 0, 320, 60)
    assert moving_box(scene.frames[0], scene.frames[1], far) is None


def test_feature_distance_and_alpha_by_hand() -> None:
    prev = PartFeatures(
        area=np.array([100.0]),
        centroid=np.zeros((1, 2)),
        wh=np.array([[10.0, 20.0]]),
        hue=np.array([350.0]),
        sigma_i=np.array([5.0]),
    )
    cur = PartFeatures(
        area=np.array([90.0, 0.0]),
        centroid=np.zeros((2, 2)),
        wh=np.array([[8.0, 20.0], [1.0, 1.0]]),
        hue=np.array([10.0, 10.0]),
        sigma_i=np.array([10.0, 5.0]),
    )
    dF = feature_distance(prev, cur)
    want = 20 / 20 + 10 / 10 + abs(0.5 - 0.4) / 0.2 + 5 / 10  # hue wraps: 350° -> 10° is 20°
    assert dF[0, 0] == pytest.approx(want)
    assert np.isnan(dF[0, 1])  # empty region
    assert occlusion_degree(dF)[0, 0] == pytest.approx(1 - np.exp(-want))
    assert occlusion_degree(dF)[0, 1] == 1.0


def test_region_features_and_matching_of_permuted_parts(scene) -> None:
    hue, sat, inten = bgr_to_hsi(scene.frames[20])
    f = region_features(scene.labels[20], 3, hue, sat, inten)
    np.testing.assert_allclose(f.area, [(scene.labels[20] == k).sum() for k in (1, 2, 3)])
    np.testing.assert_allclose(f.centroid[1:], scene.centres[20, 1:], atol=0.5)
    np.testing.assert_allclose(f.wh[1:], [[16, 30], [14, 34]])
    assert _hue_err(f.hue[2], 120) < 3
    hue2, sat2, inten2 = bgr_to_hsi(scene.frames[21])
    perm = np.array([0, 3, 1, 2])  # next frame labelled in another order
    g = region_features(perm[scene.labels[21]], 3, hue2, sat2, inten2)
    idx, alpha = match_parts(f, g)
    assert idx.tolist() == [2, 0, 1]
    assert np.all(alpha[1:] < 0.2)


def test_detection_zone_contains_points() -> None:
    zone = DetectionZone(0, 80, 60, 200)
    assert zone.contains(np.array([[20, 100], [70, 100], [30, 79]])).tolist() == [
        True,
        False,
        False,
    ]
    with pytest.raises(ValueError, match="x1 > x0"):
        DetectionZone(10, 0, 5, 5)
