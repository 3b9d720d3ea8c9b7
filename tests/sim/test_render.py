"""Synthetic video: frames show the ground truth where it says, with the stated noise/jitter."""

from __future__ import annotations

from dataclasses import replace
from itertools import islice

import cv2
import numpy as np
import pytest

from mvtrack.sim import render as R
from mvtrack.sim import scenes as S
from mvtrack.sim.backgrounds import render_background
from mvtrack.sim.style import RenderStyle, default_style


def _luma(img: np.ndarray) -> np.ndarray:
    return S.luminance(img)


def _frame(scene: S.Scene, f: int, seed: int = 0, style: RenderStyle | None = None):
    return next(islice(R.render_frames(scene, seed, style=style), f, None))


@pytest.mark.parametrize(
    "scene",
    [S.x4_nine_vehicles(), S.x5_intersection(0), S.x7_crossing(0), S.x8_splitting_group(0),
     S.crowd(30, frames=3)],
    ids=["x4", "x5", "x7", "x8", "crowd"],
)
def test_frames_have_the_scene_size_and_count(scene: S.Scene) -> None:
    frames = list(R.render_frames(scene, 1))
    assert len(frames) == scene.n_frames
    w, h = scene.size
    assert all(f.shape == (h, w, 3) and f.dtype == np.uint8 for f in frames)


def test_any_output_size_scales_the_scene() -> None:
    sc = S.x4_nine_vehicles()
    big = next(R.render_frames(sc, 0, size=(640, 480)))
    assert big.shape == (480, 640, 3)
    bg = render_background(sc, 0, size=(640, 480))
    changed = np.argwhere(np.abs(_luma(big) - _luma(bg)) > 30)
    # V1 at frame 0 is centred on (10, 84): (20, 168) at twice the size, 24×16 px.
    near = changed[np.linalg.norm(changed - [168, 20], axis=1) < 16]
    assert len(near) >= 0.9 * 24 * 16
    np.testing.assert_allclose(near.mean(axis=0), [168, 20], atol=0.6)
    with pytest.raises(ValueError, match="size"):
        next(R.render_frames(sc, 0, size=(4, 4)))


@pytest.mark.parametrize("f", [0, 60, 73, 150])
def test_x4_vehicles_are_where_the_truth_says_and_nowhere_else(f: int) -> None:
    sc = S.x4_nine_vehicles()
    img, bg = _frame(sc, f), render_background(sc)
    diff = np.abs(_luma(img) - _luma(bg))
    rows = sc.rows(f)
    yy, xx = np.mgrid[0 : 240, 0 : 320]
    covered = np.zeros((240, 320), bool)
    for xy, wh in zip(sc.xy[rows], sc.wh[rows], strict=True):
        inside = (np.abs(xx - xy[0]) <= wh[0] / 2) & (np.abs(yy - xy[1]) <= wh[1] / 2)
        covered |= (np.abs(xx - xy[0]) <= wh[0] / 2 + 1) & (np.abs(yy - xy[1]) <= wh[1] / 2 + 1)
        full = np.all(xy - wh / 2 >= 0) and np.all(xy + wh / 2 <= [319, 239])
        if full:
            hit = inside & (diff >= 60)  # luminance contrast ≥ 60 (SPEC X4)
            assert hit.sum() >= 0.85 * 12 * 8
            np.testing.assert_allclose([xx[hit].mean(), yy[hit].mean()], xy, atol=0.6)
    assert np.all(diff[~covered] == 0)  # no noise, no texture: nothing else changes


def test_x5_vehicles_are_drawn_inside_their_boxes() -> None:
    sc = S.x5_intersection(0)
    clean = replace(default_style(sc), noise_sigma=0.0, jitter=0)
    bg = render_background(sc, 3, style=clean)
    yy, xx = np.mgrid[0:240, 0:320]
    checked = 0
    for f, img in enumerate(R.render_frames(sc, 3, style=clean)):
        if f % 30:
            continue
        diff = np.abs(_luma(img) - _luma(bg)) > 25
        rows = sc.rows(f)
        covered = np.zeros((240, 320), bool)
        for i, xy, wh in zip(sc.id[rows], sc.xy[rows], sc.wh[rows], strict=True):
            box = (np.abs(xx - xy[0]) <= wh[0] / 2 + 1) & (np.abs(yy - xy[1]) <= wh[1] / 2 + 1)
            covered |= box
            if np.all(xy - wh / 2 >= 0) and np.all(xy + wh / 2 <= [319, 239]):
                body = sc.body[i - 1].prod()
                assert (diff & box).sum() >= 0.7 * body
                np.testing.assert_allclose(
                    [xx[diff & box].mean(), yy[diff & box].mean()], xy, atol=1.5
                )
                checked += 1
        assert not np.any(diff & ~covered)
    assert checked >= 10


def test_x5_has_sensor_noise_of_sigma_3_and_one_pixel_jitter() -> None:
    sc = S.x5_intersection(0)
    bg = _luma(render_background(sc, 5)).astype(np.float64)
    gray = np.array([0.114, 0.587, 0.299])
    shifts = []
    for f, img in enumerate(islice(R.render_frames(sc, 5), 12)):
        luma = _luma(img)
        (sx, sy), _ = cv2.phaseCorrelate(bg, luma)  # picture moved by (sx, sy)
        shifts.append((sx, sy))
        assert abs(sx) <= 1.1 and abs(sy) <= 1.1
        mask = np.ones((240, 320), bool)
        for xy, wh in zip(sc.xy[sc.rows(f)], sc.wh[sc.rows(f)], strict=True):
            x0, y0 = np.floor(xy - wh / 2 - 3).astype(int)
            x1, y1 = np.ceil(xy + wh / 2 + 3).astype(int)
            mask[max(y0, 0) : y1, max(x0, 0) : x1] = False
        warp = np.array([[1.0, 0.0, sx], [0.0, 1.0, sy]])
        moved = cv2.warpAffine(bg, warp, (320, 240), flags=cv2.INTER_LINEAR)
        m = mask[3:-3, 3:-3]
        resid = (luma - moved)[3:-3, 3:-3][m]
        still = (luma - bg)[3:-3, 3:-3][m]
        # Luma of independent σ = 3 noise per channel has σ = 3·|(0.114, 0.587, 0.299)|; the
        # re-interpolated background adds a little on top.
        assert np.std(resid) == pytest.approx(3 * np.linalg.norm(gray), rel=0.25)
        if max(abs(sx), abs(sy)) > 0.4:
            assert np.std(still) > 1.3 * np.std(resid)  # the shift is real, not noise
    shifts = np.array(shifts)
    assert shifts.std(axis=0).min() > 0.2  # the camera does shake, differently each frame


def test_x8_car_is_drawn_over_the_lower_halves_of_the_people() -> None:
    sc = S.x8_splitting_group(0)
    clean = replace(default_style(sc), noise_sigma=0.0)
    bg = render_background(sc, 0, style=clean)
    img = _frame(sc, 56, style=clean)
    changed = np.abs(img.astype(int) - bg.astype(int)).sum(axis=2) > 30
    p2 = sc.xy[(sc.frame == 56) & (sc.id == 2)][0]  # P2 behind the car, at (85.2, 56.8)
    x, y = np.round(p2).astype(int)
    assert changed[y - 6 : y - 1, x - 3 : x + 4].mean() > 0.5  # his upper half shows
    # his lower half is the car (its left edge shows P3's upper half, beside him)
    assert not changed[y + 1 : y + 8, x + 1 : x + 5].any()
    early = _frame(sc, 20, style=clean)  # the group is in the open at frame 20
    p2 = sc.xy[(sc.frame == 20) & (sc.id == 2)][0].round().astype(int)
    patch = (slice(p2[1] - 6, p2[1] + 7), slice(p2[0] - 3, p2[0] + 4))
    assert np.abs(_luma(early[patch]) - _luma(bg[patch])).mean() > 25


def test_same_seed_same_frames_other_seed_other_frames() -> None:
    sc = S.x5_intersection(0)
    a = list(islice(R.render_frames(sc, 11), 5))
    b = list(islice(R.render_frames(sc, 11), 5))
    c = list(islice(R.render_frames(sc, 12), 5))
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])


def test_write_video_gives_a_readable_mp4_and_no_temporary_files(tmp_path) -> None:
    sc = S.x4_nine_vehicles().truncate(30)
    path = R.write_video(sc, tmp_path / "v.mp4", seed=0, progress=False)
    assert [p.name for p in tmp_path.iterdir()] == ["v.mp4"]
    cap = cv2.VideoCapture(str(path))
    n, frames = 0, []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
        n += 1
    cap.release()
    assert n == 30 and frames[0].shape == (240, 320, 3)
    ref = _frame(sc, 10).astype(float)
    assert np.abs(frames[10].astype(float) - ref).mean() < 4  # lossy codec, same picture


def test_write_video_leaves_nothing_when_rendering_fails(tmp_path, monkeypatch) -> None:
    def broken(*args, **kwargs):
        yield np.zeros((240, 320, 3), np.uint8)
        raise RuntimeError("boom")

    monkeypatch.setattr(R, "render_frames", broken)
    with pytest.raises(RuntimeError, match="boom"):
        R.write_video(S.x4_nine_vehicles(), tmp_path / "v.mp4", progress=False)
    assert list(tmp_path.iterdir()) == []


def test_bad_style_is_refused() -> None:
    with pytest.raises(ValueError, match="background"):
        RenderStyle(background="space")
    with pytest.raises(ValueError):
        RenderStyle(noise_sigma=-1)
