"""A track that ends behind an occluder is continued by the new track that starts where it
should reappear and looks the same (``mvtrack.video.relink``)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mvtrack.config import RelinkSettings, RunSettings
from mvtrack.types import TrackFrame, TrackState
from mvtrack.video import relink as relink_module
from mvtrack.video.relink import (
    BINS,
    GREYS,
    HUES,
    MIN_SATURATION,
    SATS,
    Relinker,
    box_histograms,
)
from mvtrack.video.run import track_to_folder

RED, BLUE = (40, 40, 220), (220, 60, 40)  # BGR


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("seed", [0, 1])
def test_box_histograms_count_the_sampled_pixels_of_each_box(seed, compiled, monkeypatch) -> None:
    if not compiled:  # the plain functions the kernels are compiled from
        monkeypatch.setattr(relink_module, "sample_pixels", relink_module.sample_pixels.py_func)
        monkeypatch.setattr(relink_module, "count_bins", relink_module.count_bins.py_func)
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, (50, 70, 3), dtype=np.uint8)
    boxes = np.column_stack([rng.uniform(-10, 60, (6, 2)), rng.uniform(3, 30, (6, 2))])
    boxes[2] = [80.0, 10.0, 5.0, 5.0]  # outside the image: zeros
    got = box_histograms(img, boxes)
    for b, row in zip(boxes, got, strict=True):  # the reference: one box at a time
        x0 = int(np.clip(b[0] + 0.2 * b[2], 0, 70))
        x1 = int(np.clip(b[0] + 0.8 * b[2], 0, 70))
        y0 = int(np.clip(b[1] + 0.1 * b[3], 0, 50))
        y1 = int(np.clip(b[1] + 0.9 * b[3], 0, 50))
        ref = np.zeros(BINS)
        for y in range(y0, y1, 2):
            for x in range(x0, x1, 2):
                h, s, v = cv2.cvtColor(img[y : y + 1, x : x + 1], cv2.COLOR_BGR2HSV)[0, 0]
                if s >= MIN_SATURATION:
                    ref[(int(h) * HUES // 180) * SATS + int(s) * SATS // 256] += 1
                else:
                    ref[HUES * SATS + int(v) * GREYS // 256] += 1
        if ref.sum():
            ref /= ref.sum()
        np.testing.assert_array_equal(row, ref)
    assert not got[2].any()
    assert box_histograms(img, np.zeros((0, 4))).shape == (0, BINS)
    nan = box_histograms(img, np.array([[np.nan, 5.0, 10.0, 10.0], [5.0, 5.0, 20.0, 20.0]]))
    assert not nan[0].any() and nan[1].sum() == pytest.approx(1.0)


def _frame(k: int, ids: list[int], xs: list[float], vx: float = 3.0) -> TrackFrame:
    n = len(ids)
    xy = np.column_stack([np.asarray(xs, float), np.full(n, 60.0)])
    return TrackFrame(
        k, np.asarray(ids, np.int64), np.full(n, int(TrackState.CONFIRMED), np.int64),
        np.arange(n, dtype=np.int64), xy.copy(), xy.copy(), xy.copy(),
        np.tile([12.0, 30.0], (n, 1)), np.tile([vx, 0.0], (n, 1)),
    )


def _image(people: list[tuple[float, tuple[int, int, int]]]) -> np.ndarray:
    img = np.full((120, 240, 3), 128, np.uint8)
    for x, colour in people:
        img[45:75, int(x) - 6 : int(x) + 6] = colour
    return img


def _occlusion(colour, at: float, start: int = 28, settings: RelinkSettings | None = None
               ) -> tuple[list[int], Relinker]:
    """Track 1 (red) walks right at 3 px/frame, is hidden from frame 20 and deleted at 23;
    track 2 (``colour``) starts at frame ``start`` at x = ``at``. The shown IDs of track 2."""
    rl = Relinker(10.0, settings)
    shown = []
    for k in range(start + 3):
        x = 20 + 3 * k
        if k < 20:
            tf, img, live = _frame(k, [1], [x]), _image([(x, RED)]), [1]
        elif k < start:
            tf, img, live = _frame(k, [], []), _image([]), [1] if k < 23 else []
        else:
            xa = at + 3 * (k - start)
            tf, img, live = _frame(k, [2], [xa]), _image([(xa, colour)]), [2]
        out = rl(img, tf, np.asarray(live, np.int64))
        if k >= start:
            shown.append(int(out.track_id[0]))
    return shown, rl


def test_the_new_track_where_the_hidden_one_reappears_takes_its_id() -> None:
    shown, rl = _occlusion(RED, at=20 + 3 * 28)
    assert shown == [1, 1, 1]
    assert rl.links == [(1, 2, 28)]
    assert rl.shown(np.array([2, 5])).tolist() == [1, 5]


@pytest.mark.parametrize(
    ("colour", "at", "why"),
    [(BLUE, 20 + 3 * 28, "looks different"), (RED, 20 + 3 * 28 + 40, "too far from where "
     "the hidden one would be"), (RED, 20 + 3 * 8, "back where it was: not a reappearance")],
)
def test_no_link_when_the_new_track_is_another_object(colour, at, why) -> None:
    shown, rl = _occlusion(colour, at=at)
    assert shown == [2, 2, 2], why
    assert rl.links == []


def test_the_radius_grows_with_the_time_hidden() -> None:
    # 25 px short of where the hidden one would be (it slowed down or turned): beyond
    # reach·h = 0.5 · 30 = 15 px, within (0.5 + 0.5 · 0.9 s) · 30 = 28.5 px after 9 frames
    at = 20 + 3 * 28 - 25
    assert _occlusion(RED, at=at)[0] == [1, 1, 1]
    assert _occlusion(RED, at=at, settings=RelinkSettings(spread=0.0))[0] == [2, 2, 2]
    # the same distance four frames after its last row: (0.5 + 0.5 · 0.4 s) · 30 = 21 px < 25
    assert _occlusion(RED, at=20 + 3 * 23 - 25, start=23)[0] == [2, 2, 2]


def test_no_link_after_the_window() -> None:
    shown, _ = _occlusion(RED, at=20 + 3 * 60, start=60)  # 4 s later, window 2 s
    assert shown == [2, 2, 2]


def test_relink_settings_are_checked() -> None:
    with pytest.raises(ValueError, match="min_similarity"):
        RelinkSettings(min_similarity=1.5)
    with pytest.raises(ValueError, match="window"):
        RelinkSettings(window=0)


def _pole_video(n: int = 60) -> list[np.ndarray]:
    """A red 10×24 walker crossing a 36 px wide grey pole at 3 px/frame (hidden ~9 frames)."""
    frames = []
    rng = np.random.default_rng(0)
    for k in range(n):
        img = np.full((120, 200, 3), 50, np.uint8)
        img = (img + rng.normal(0, 2, img.shape)).clip(0, 255).astype(np.uint8)
        x = -12 + 3 * k  # enters from the left: the first frame is the empty street
        img[50:74, max(x, 0) : max(x + 10, 0)] = RED
        img[:, 90:126] = (150, 150, 150)  # the pole, in front
        frames.append(img)
    return frames


def test_a_walker_behind_a_pole_keeps_one_id_through_the_pipeline(tmp_path) -> None:
    frames = _pole_video()
    ids, sides = {}, {}
    for name, relink in (("on", RelinkSettings()), ("off", RelinkSettings(enabled=False))):
        # no template matching: it would hold the walker at the pole's edge as a stopped
        # vehicle (the walker's last template matches the edge), and nothing would end
        settings = RunSettings(video=False, detector="disturbance-map", templates=False,
                               relink=relink)
        run = track_to_folder(frames, fps=10.0, size=(200, 120), settings=settings,
                              out=tmp_path / name, progress=False)
        cols = run.log.columns()
        ids[name] = sorted(set(cols["track_id"][cols["track_id"] > 0].tolist()))
        rows = np.loadtxt(tmp_path / name / "results.txt", delimiter=",", ndmin=2)
        assert sorted(set(rows[:, 1].astype(int).tolist())) == ids[name]
        x = rows[:, 2] + rows[:, 4] / 2
        sides[name] = (set(rows[x < 90, 1].astype(int)), set(rows[x > 126, 1].astype(int)))
    # the tracker alone: the walker has one ID before the pole and another after it
    before, after = sides["off"]
    assert before and after and not before & after and len(after) == 1, sides["off"]
    assert ids["on"] == [1]  # relinked: one ID from the first row to the last
