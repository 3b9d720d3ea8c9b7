"""The scene front end on scenarios built from real frames of KITTI-17.

Two real people (their silhouettes cut from frame 120 with the ground-truth boxes, against the
clip's median background) are moved over the real background, at half size (612×185):
side by side and then apart; across the edge of a shadow; parked for minutes. The ground
truth of each scenario is known by construction.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from mvtrack.detection.adaptive import GaussianBackground, temporal_median
from mvtrack.detection.feedback import detect_with_tracker
from mvtrack.detection.scene_frontend import SceneFrontEnd
from mvtrack.detection.shadows import shadow_mask
from mvtrack.detection.sizeprior import SizePrior
from mvtrack.eval import iou_matrix
from mvtrack.io.mot import read_tracks
from mvtrack.tracking import Tracker, TrackerConfig, track_detections

pytestmark = pytest.mark.shared

SCALE = 0.5
PEOPLE = (7, 8)  # side by side, not touching, in frame 120
FRAME = 120


class Patch:
    """A person's pixels (BGR) and silhouette, cut from a real frame."""

    def __init__(self, pixels: np.ndarray, sil: np.ndarray) -> None:
        self.pixels, self.sil = pixels, sil

    @property
    def wh(self) -> tuple[int, int]:
        return self.sil.shape[1], self.sil.shape[0]


@pytest.fixture(scope="module")
def kitti(shared_dir: Path) -> tuple[np.ndarray, list[Patch]]:
    seq = shared_dir / "data" / "real" / "KITTI-17"
    paths = sorted((seq / "img1").glob("*.jpg"))

    def half(p: Path) -> np.ndarray:
        return cv2.resize(cv2.imread(str(p)), None, fx=SCALE, fy=SCALE,
                          interpolation=cv2.INTER_AREA)

    bg = temporal_median([half(p) for p in paths[::5]])
    frame = half(paths[FRAME - 1])
    gt = read_tracks(seq / "gt.txt", "gt")
    patches = []
    for pid in PEOPLE:
        row = np.flatnonzero((gt.frame == FRAME - 1) & (gt.id == pid))[0]
        x, y, w, h = np.round(gt.tlwh[row] * SCALE).astype(int)
        f = frame[y : y + h, x : x + w]
        b = bg[y : y + h, x : x + w]
        diff = np.abs(f.astype(np.int16) - b.astype(np.int16)).max(axis=2) > 25
        sil = diff.astype(np.uint8) * 255
        shadow = shadow_mask(f.astype(np.float32), b.astype(np.float32), sil)
        sil[shadow > 0] = 0
        sil = cv2.morphologyEx(sil, cv2.MORPH_CLOSE, np.ones((5, 3), np.uint8))
        ys, xs = np.nonzero(sil)
        sil = sil[ys.min() : ys.max() + 1, xs.min() : xs.max() + 1]
        f = f[ys.min() : ys.max() + 1, xs.min() : xs.max() + 1]
        patches.append(Patch(f.copy(), sil))
    return bg, patches


def paste(img: np.ndarray, patch: Patch, left: int, bottom: int) -> tuple[float, ...]:
    """Draw ``patch`` with its foot row at ``bottom``; its true box (tlwh, blob convention)."""
    w, h = patch.wh
    top = bottom - h + 1
    region = img[top : top + h, left : left + w]
    on = patch.sil > 0
    region[on] = patch.pixels[on]
    return (left - 0.5, top - 0.5, float(w), float(h))


def taught_prior(patches: list[Patch], foot: int) -> SizePrior:
    """A prior that has seen these people at rows around ``foot`` (as if earlier in the clip)."""
    prior = SizePrior(min_samples=10, min_spread=10)
    boxes = []
    for i, p in enumerate(patches * 10):
        w, h = p.wh
        for dy in (-8, 8):  # the same people a little nearer and farther away
            s = (foot + dy - 60) / (foot - 60)
            boxes.append((100 + i, foot + dy - s * h, s * w, s * h))
    prior.update(np.array(boxes))
    return prior


def config() -> TrackerConfig:
    return TrackerConfig(fps=10.0)


def test_two_people_side_by_side_then_apart_give_two_tracks_throughout(kitti) -> None:
    bg, (a, b) = kitti
    foot = 175  # on the open pavement
    truth = []
    frames = []
    n = 30
    for k in range(n):
        img = bg.copy()
        xa = 340 + 3 * k
        # side by side, 3 px apart (one blob after the closing), then B pulls ahead
        gap = 3 if k < 15 else 3 + 4 * (k - 15)
        xb = xa + a.wh[0] + gap
        ta = paste(img, a, xa, foot)
        tb = paste(img, b, xb, foot)
        truth.append((ta, tb))
        frames.append(img)
    fe = SceneFrontEnd(work_pixels=0, prior=taught_prior([a, b], foot))
    fe.bootstrap([bg])
    dets = detect_with_tracker(frames, fe, Tracker(config()), learn=False)
    assert all(len(d) == 2 for d in dets[1:]), [len(d) for d in dets]
    log = track_detections(dets, config())
    rows = log.to_mot()
    ids = np.unique(rows[:, 1])
    assert len(ids) == 2, ids
    for person in (0, 1):
        owner = []
        for k in range(2, n):
            r = rows[rows[:, 0] == k + 1]
            iou = iou_matrix(np.array([truth[k][person]]), r[:, 2:6])[0]
            owner.append(r[np.argmax(iou), 1] if iou.max() >= 0.45 else -1)
        # one ID follows the person, side by side and apart: matched (IoU >= 0.45) in all
        # but at most two frames, and never by another ID. (While they walk side by side
        # the split blob's boxes themselves overlap person B by IoU 0.47-0.51 only; the
        # tracker's box, smoothed, at 0.49-0.61, and 0.49 in the two frames in which B
        # pulls ahead.)
        matched = [o for o in owner if o > 0]
        assert len(matched) >= len(owner) - 2 and len(set(matched)) == 1, owner


def test_person_crossing_a_shadow_edge_keeps_one_box_of_the_right_size(kitti) -> None:
    bg, (a, b) = kitti
    edge = 420  # columns right of the edge are in shade (a wall's shadow): 45 % of the light
    shade = np.ones(bg.shape, np.float32)
    shade[:, edge:] = (0.50, 0.45, 0.42)  # skylight: blue darkens least
    shaded_bg = np.clip(bg * shade, 0, 255).astype(np.uint8)
    foot = 165
    # the scene's size prior, learnt earlier: it completes a head lost against the dark wall
    fe = SceneFrontEnd(work_pixels=0, prior=taught_prior([a, b], foot))
    fe.bootstrap([shaded_bg])
    lit, shaded, cast = [], [], []
    for k in range(40):
        img = bg.copy()
        box = paste(img, a, 330 + 4 * k, foot)
        # the person's own cast shadow: a band of ground to the right of the feet
        x0 = int(box[0] + box[2])
        img[foot - 4 : foot + 1, x0 : x0 + 40] = (img[foot - 4 : foot + 1, x0 : x0 + 40] * 0.35)
        frame = np.clip(img * shade, 0, 255).astype(np.uint8)
        dets = fe(frame, k)
        if k == 0:
            continue
        # the cast shadow itself is not foreground (away from the feet, which the closing
        # may reach): the shadow test, not only the box trimming, takes it out
        band = fe.mask[foot - 4 : foot + 1, x0 + 8 : x0 + 40]
        cast.append(float((band > 0).mean()))
        iou = iou_matrix(np.array([box]), dets.tlwh)[0]
        assert (iou > 0.1).sum() == 1, (k, dets.tlwh)  # one box on the person
        j = int(np.argmax(iou))
        left, _, w, h = dets.tlwh[j]
        assert iou[j] >= 0.5, (k, iou[j], dets.tlwh[j], box)
        # not stretched over the cast shadow on the right
        assert left + w <= box[0] + box[2] + 0.15 * box[2], (k, dets.tlwh[j], box)
        if box[0] + box[2] < edge:
            lit.append((w, h))
        elif box[0] > edge:
            shaded.append((w, h))
    assert len(lit) >= 10 and len(shaded) >= 10
    assert np.median(cast) < 0.1, cast
    # the same size in the sun and in the shade
    np.testing.assert_allclose(np.median(shaded, 0), np.median(lit, 0), rtol=0.15)


def test_parked_object_fades_on_the_slow_path_not_within_seconds(kitti) -> None:
    bg, (a, _) = kitti
    crop = bg[60:185, 330:500].copy()
    model = GaussianBackground()
    model.bootstrap(crop)
    parked = crop.copy()
    box = paste(parked, a, 40, 110)
    x0, y0 = int(box[0] + 0.5), int(box[1] + 0.5)
    sil = a.sil > 0
    fps = 10
    share = []
    for _ in range(90 * fps):  # 90 s at 10 fps
        mask = model.apply(parked)
        region = mask[y0 : y0 + sil.shape[0], x0 : x0 + sil.shape[1]]
        share.append(float((region[sil] > 0).mean()))
    share = np.array(share)
    assert share[: 10 * fps].min() > 0.7  # all there after 10 s
    half = int(np.argmax(share < 0.5)) / fps
    assert 20 < half < 60, half  # the slow leak: not within seconds
    assert share[61 * fps :].max() < 0.05  # absorbed whole after 600 frames


def test_ghost_of_a_person_in_the_first_frame_is_removed(kitti) -> None:
    bg, (a, _) = kitti
    first = bg.copy()
    box = paste(first, a, 350, 165)
    model = GaussianBackground(ghost_every=5)
    model.bootstrap(first)  # started with the person in view: their ghost is in the model
    x0, y0 = int(box[0] + 0.5), int(box[1] + 0.5)
    sil = a.sil > 0
    share = []
    for _ in range(12):
        mask = model.apply(bg)  # the person has left
        share.append(float((mask[y0 : y0 + sil.shape[0], x0 : x0 + sil.shape[1]][sil] > 0).mean()))
    assert share[0] > 0.5  # the ghost shows at first
    assert max(share[5:]) < 0.05  # and is reset at the first ghost test
    no_removal = GaussianBackground(ghost_every=0)
    no_removal.bootstrap(first)
    for _ in range(12):
        mask = no_removal.apply(bg)
    assert (mask[y0 : y0 + sil.shape[0], x0 : x0 + sil.shape[1]][sil] > 0).mean() > 0.5


def test_jitter_of_one_pixel_lights_few_pixels_with_the_neighbourhood_model(kitti) -> None:
    bg, _ = kitti
    shifted = np.roll(bg, 1, axis=1)  # the camera moved by one pixel
    lit = {}
    for j in (0, 1):
        model = GaussianBackground(jitter=j, shadows=False, ghost_every=0)
        model.bootstrap(bg)
        lit[j] = float((model.apply(shifted)[:, 1:] > 0).mean())
    assert lit[1] < 0.01 < lit[0], lit
