"""Detection-level simulation: miss rate, clutter, noise, shuffling and visibility."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.sim.crowd import crowd
from mvtrack.sim.detections import detections_from_scene, detections_with_truth
from mvtrack.sim.nine_vehicles import x4_nine_vehicles
from mvtrack.sim.splitting_group import x8_splitting_group


@pytest.fixture(scope="module")
def big():
    sc = crowd(500, frames=200, seed=1)
    dets, ids = detections_with_truth(sc, np.random.default_rng(2))
    return sc, dets, ids


def _truth_of(sc, f, ids):
    rows = sc.rows(f)
    lookup = {int(i): k for k, i in enumerate(sc.id[rows])}
    k = np.array([lookup[int(i)] for i in ids], dtype=np.int64)
    return sc.xy[rows][k], sc.wh[rows][k]


def test_one_detections_per_frame_in_order(big) -> None:
    sc, dets, ids = big
    assert len(dets) == sc.n_frames == len(ids)
    assert [d.frame for d in dets] == list(range(sc.n_frames))
    assert all(len(d) == len(i) for d, i in zip(dets, ids, strict=True))


def test_miss_rate_is_about_one_tenth(big) -> None:
    sc, _, ids = big
    detected = sum(int(np.sum(i > 0)) for i in ids)
    rate = 1 - detected / int(sc.visible.sum())  # 100 000 rows: σ ≈ 0.001
    assert rate == pytest.approx(0.1, abs=0.006)


def test_clutter_is_poisson_with_mean_three() -> None:
    sc = crowd(5, frames=3000, seed=0)
    _, ids = detections_with_truth(sc, np.random.default_rng(5))
    fa = np.array([np.sum(i < 0) for i in ids])
    assert fa.mean() == pytest.approx(3.0, abs=0.15)  # σ of the mean ≈ 0.03
    assert fa.var() == pytest.approx(3.0, rel=0.15)  # Poisson: variance = mean


def test_false_alarms_fall_inside_the_image_with_plausible_sizes(big) -> None:
    _, dets, ids = big
    xy = np.concatenate([d.xy[i < 0] for d, i in zip(dets, ids, strict=True)])
    wh = np.concatenate([d.wh[i < 0] for d, i in zip(dets, ids, strict=True)])
    assert np.all((xy >= 0) & (xy <= [1920, 1080]))
    assert xy[:, 0].mean() == pytest.approx(960, rel=0.05)
    # sizes of the scene's own boxes (40×30 ±10 %) plus σ = 1 px noise
    assert np.all((wh > [30, 21]) & (wh < [50, 39]))


def test_centre_and_size_noise_have_the_stated_sigma(big) -> None:
    sc, dets, ids = big
    dxy, dwh = [], []
    for f in range(0, sc.n_frames, 4):
        keep = ids[f] > 0
        xy, wh = _truth_of(sc, f, ids[f][keep])
        dxy.append(dets[f].xy[keep] - xy)
        dwh.append(dets[f].wh[keep] - wh)
    dxy, dwh = np.concatenate(dxy), np.concatenate(dwh)
    np.testing.assert_allclose(dxy.std(axis=0), [2.0, 2.0], rtol=0.03)
    np.testing.assert_allclose(dwh.std(axis=0), [1.0, 1.0], rtol=0.03)
    np.testing.assert_allclose(dxy.mean(axis=0), [0, 0], atol=0.05)


def test_rows_are_shuffled_unless_asked_not_to() -> None:
    sc = crowd(50, frames=3, seed=0)
    _, ids = detections_with_truth(sc, np.random.default_rng(0), clutter=0.0)
    assert not np.all(np.diff(ids[0]) > 0)
    _, ids = detections_with_truth(sc, np.random.default_rng(0), clutter=0.0, shuffle=False)
    assert np.all(np.diff(ids[0]) > 0)


def test_noise_free_detections_equal_the_truth() -> None:
    sc = x4_nine_vehicles()
    dets, ids = detections_with_truth(
        sc, np.random.default_rng(0), pos_sigma=0, size_sigma=0, miss=0, clutter=0
    )
    for f in (0, 73, 200):
        xy, wh = _truth_of(sc, f, ids[f])
        np.testing.assert_array_equal(dets[f].xy, xy)
        np.testing.assert_array_equal(dets[f].wh, wh)
        assert len(dets[f]) == int(sc.visible[sc.rows(f)].sum())


def test_hidden_objects_are_never_detected() -> None:
    sc = x8_splitting_group(0)
    _, ids = detections_with_truth(sc, np.random.default_rng(1), miss=0.0, clutter=0.0)
    hidden = ~sc.visible
    assert hidden.sum() > 0
    for f, i in zip(sc.frame[hidden], sc.id[hidden], strict=True):
        assert i not in ids[f]


def test_same_generator_state_same_detections() -> None:
    sc = crowd(20, frames=10, seed=0)
    a = detections_from_scene(sc, np.random.default_rng(9))
    b = detections_from_scene(sc, np.random.default_rng(9))
    for da, db in zip(a, b, strict=True):
        np.testing.assert_array_equal(da.xy, db.xy)


@pytest.mark.parametrize(
    "kwargs", [{"miss": 1.5}, {"miss": -0.1}, {"clutter": -1.0}, {"pos_sigma": float("nan")}]
)
def test_bad_parameters_are_refused(kwargs) -> None:
    with pytest.raises(ValueError, match=next(iter(kwargs))):
        detections_from_scene(crowd(2, frames=2), np.random.default_rng(0), **kwargs)
