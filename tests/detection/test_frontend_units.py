"""Size prior, split/merge, shadows, adapters and HOG of the real-video front end."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from mvtrack.detection.adapters import (
    CallableDetector,
    from_supervision,
    from_ultralytics,
    to_supervision,
)
from mvtrack.detection.adaptive import temporal_median
from mvtrack.detection.shadows import shadow_mask
from mvtrack.detection.sizeprior import SizePrior, quantile_line, robust_line
from mvtrack.detection.splitmerge import MERGED, PLAIN, SPLIT, split_merge
from mvtrack.types import Detections

# ---------------------------------------------------------------- size prior


def perspective_boxes(rng: np.random.Generator, n: int, outliers: float = 0.2) -> np.ndarray:
    """People on a ground plane: height 0.8 (y - 60) at foot row y, width 0.4 × height, 3 %
    noise; ``outliers`` of them partial bodies (half height) or pairs (double width)."""
    foot = rng.uniform(120, 470, n)
    h = 0.8 * (foot - 60) * rng.normal(1, 0.03, n)
    w = 0.4 * h * rng.normal(1, 0.03, n)
    kind = rng.random(n)
    part = kind < outliers / 2
    pair = (kind >= outliers / 2) & (kind < outliers)
    h = np.where(part, 0.5 * h, h)
    w = np.where(pair, 2.0 * w, w)
    x = rng.uniform(0, 600, n)
    return np.column_stack([x, foot - h, w, h])


def test_size_prior_of_a_synthetic_perspective_scene_matches_its_construction() -> None:
    rng = np.random.default_rng(3)
    prior = SizePrior(quantile=None)  # the middle of the data, Tukey's biweight
    for _ in range(40):  # online: ten boxes a frame
        prior.update(perspective_boxes(rng, 10))
    assert prior.ready
    rows = np.array([150.0, 250.0, 350.0, 450.0])
    true_h = 0.8 * (rows - 60)
    got = prior.expected(rows)
    np.testing.assert_allclose(got[:, 1], true_h, rtol=0.10)
    np.testing.assert_allclose(got[:, 0], 0.4 * true_h, rtol=0.10)
    # boxes no object of the scene could have: a 40 px tall box standing at row 450
    assert prior.plausible([[0, 410, 30, 40], [0, 138, 124, 312]]).tolist() == [False, True]


def test_size_prior_waits_for_spread_out_samples_and_the_upper_quantile_follows_whole_bodies():
    rng = np.random.default_rng(4)
    prior = SizePrior()
    prior.update(np.tile([[0.0, 100.0, 20.0, 50.0]], (50, 1)))  # all at one row: no slope
    assert not prior.ready and np.isnan(prior.expected([100])).all()
    boxes = perspective_boxes(rng, 400, outliers=0.0)
    heights = boxes[:, 3].copy()
    boxes[::3, 3] *= 0.6  # a third are partial bodies (legs lost)
    boxes[::3, 1] += heights[::3] * 0.4
    prior.update(boxes)
    h = prior.expected([300.0])[0, 1]
    assert abs(h / (0.8 * 240) - 1) < 0.10, h  # whole bodies, not pulled down by the parts


def test_robust_and_quantile_lines_against_closed_forms() -> None:
    x = np.arange(20.0)
    y = 3.0 + 0.5 * x
    a, b, s = robust_line(x, y)
    assert abs(a - 3) < 1e-9 and abs(b - 0.5) < 1e-9 and s < 1e-9
    y2 = y.copy()
    y2[::5] += 100.0  # four gross outliers
    a, b, _ = robust_line(x, y2)
    assert abs(a - 3) < 1e-6 and abs(b - 0.5) < 1e-6
    # quantile line of y = x + u, u uniform in [0, 1): the 0.75 quantile is x + 0.75
    rng = np.random.default_rng(0)
    xs = rng.uniform(0, 10, 4000)
    a, b, _ = quantile_line(xs, xs + rng.random(4000), 0.75)
    assert abs(a - 0.75) < 0.05 and abs(b - 1.0) < 0.01


# ---------------------------------------------------------------- split / merge


def _rect(mask: np.ndarray, x: int, y: int, w: int, h: int) -> tuple[float, ...]:
    mask[y : y + h, x : x + w] = 255
    return (x - 0.5, y - 0.5, float(w), float(h))


def test_a_blob_that_two_predicted_boxes_fall_into_is_split_between_them() -> None:
    mask = np.zeros((120, 200), np.uint8)
    _rect(mask, 40, 20, 20, 80)
    _rect(mask, 60, 30, 20, 70)  # a second person touching the first: one blob
    blob = np.array([[39.5, 19.5, 40.0, 80.0]])
    pred = np.array([[38.0, 20.0, 22.0, 80.0], [60.0, 30.0, 20.0, 70.0]])
    boxes, flags = split_merge(blob, mask, pred)
    assert flags.tolist() == [SPLIT, SPLIT]
    np.testing.assert_allclose(boxes[np.argsort(boxes[:, 0])], [[39.5, 19.5, 20, 80],
                                                               [59.5, 29.5, 20, 70]], atol=1.0)


def test_fragments_inside_one_predicted_box_are_merged_and_plain_blobs_stay_plain() -> None:
    mask = np.zeros((120, 200), np.uint8)
    top = _rect(mask, 40, 20, 20, 30)  # head and torso
    legs = _rect(mask, 42, 60, 16, 40)  # legs, 10 rows below
    other = _rect(mask, 150, 30, 20, 60)
    pred = np.array([[38.0, 18.0, 24.0, 84.0]])
    boxes, flags = split_merge(np.array([top, legs, other]), mask, pred)
    assert sorted(flags.tolist()) == [PLAIN, MERGED]
    np.testing.assert_allclose(boxes[flags == MERGED][0], [39.5, 19.5, 20, 80])
    np.testing.assert_allclose(boxes[flags == PLAIN][0], other)


def test_an_over_wide_blob_is_cut_where_the_silhouette_dips_between_two_heads() -> None:
    prior = SizePrior(min_samples=2, min_spread=1)
    prior.update([[0, 20, 20, 80], [0, 0, 15, 60]])  # h = 20 + y / 2, a quarter as wide
    mask = np.zeros((120, 200), np.uint8)
    _rect(mask, 40, 20, 20, 80)
    _rect(mask, 60, 24, 20, 76)  # shoulders touch below the heads
    mask[20:40, 57:63] = 0  # the dip between the heads
    boxes, flags = split_merge(np.array([[39.5, 19.5, 40.0, 80.0]]), mask, None, prior)
    assert flags.tolist() == [SPLIT, SPLIT]
    np.testing.assert_allclose(np.sort(boxes[:, 0]), [39.5, 59.5], atol=3)  # in the dip
    # a single wide walker (an arm out to one side, no second head) is not cut
    lone = np.zeros((120, 200), np.uint8)
    _rect(lone, 40, 20, 20, 80)
    _rect(lone, 60, 50, 22, 6)  # the arm
    boxes, flags = split_merge(np.array([[39.5, 19.5, 42.0, 80.0]]), lone, None, prior)
    assert flags.tolist() == [PLAIN]


# ---------------------------------------------------------------- shadows, median


def test_shadow_mask_takes_a_darker_same_colour_pixel_and_not_a_different_colour() -> None:
    mean = np.full((1, 3, 3), (60.0, 120.0, 180.0), np.float32)
    frame = np.array([[[30, 60, 90], [120, 60, 30], [59, 121, 181]]], np.float32)
    cand = np.array([[255, 255, 0]], np.uint8)
    out = shadow_mask(frame, mean, cand, texture=2.0)
    # half the light, same chromaticity: shadow; other colour: object; not a candidate: no
    assert out.tolist() == [[255, 0, 0]]


def test_temporal_median_removes_a_person_present_in_a_minority_of_frames() -> None:
    bg = np.full((10, 10, 3), 100, np.uint8)
    frames = [bg.copy() for _ in range(9)]
    for f in frames[:4]:
        f[2:6, 2:6] = 10  # someone standing there in 4 of 9 frames
    np.testing.assert_array_equal(temporal_median(frames), bg)
    with pytest.raises(ValueError, match="no frames"):
        temporal_median([])


@pytest.mark.parametrize("n", [1, 2, 3, 8, 9, 16, 17])
def test_temporal_median_equals_numpys_median_rounded(n: int) -> None:
    """The sorting network for a few frames against ``np.median`` (ties and halves included:
    even counts take the mean of the two middle values, rounded half to even)."""
    rng = np.random.default_rng(n)
    frames = [rng.integers(0, 256, (12, 16, 3), dtype=np.uint8) for _ in range(n)]
    frames += [rng.integers(100, 104, (12, 16, 3), dtype=np.uint8) for _ in range(n)]
    copies = [f.copy() for f in frames]
    expected = np.median(np.stack(frames), axis=0).round().astype(np.uint8)
    got = temporal_median(frames, max_frames=64)
    assert got.dtype == np.uint8
    np.testing.assert_array_equal(got, expected)
    for f, c in zip(frames, copies, strict=True):  # the frames given are left as they were
        np.testing.assert_array_equal(f, c)


# ---------------------------------------------------------------- adapters


def test_supervision_detections_both_ways() -> None:
    import supervision as sv  # a test dependency (pyproject: test extra)

    det = sv.Detections(
        xyxy=np.array([[10, 20, 50, 120], [100, 0, 130, 60]], np.float32),
        confidence=np.array([0.9, 0.4], np.float32),
        class_id=np.array([0, 0]),
    )
    ours = from_supervision(det, frame=7)
    assert ours.frame == 7
    np.testing.assert_allclose(ours.tlwh, [[10, 20, 40, 100], [100, 0, 30, 60]])
    np.testing.assert_allclose(ours.score, [0.9, 0.4], rtol=1e-6)
    back = to_supervision(ours, tracker_id=[3, 5])
    assert isinstance(back, sv.Detections)
    np.testing.assert_allclose(back.xyxy, det.xyxy)
    assert back.tracker_id.tolist() == [3, 5]
    # supervision's own annotator draws our boxes
    img = np.zeros((150, 150, 3), np.uint8)
    drawn = sv.BoxAnnotator(color_lookup=sv.ColorLookup.TRACK).annotate(img.copy(), back)
    assert drawn.any()


class _Tensor:
    """Stands in for a torch tensor: ``.cpu().numpy()``."""

    def __init__(self, a):
        self.a = np.asarray(a)

    def cpu(self):
        return self

    def numpy(self):
        return self.a


def _ultralytics_result(xyxy, conf, cls):
    return SimpleNamespace(boxes=SimpleNamespace(xyxy=_Tensor(xyxy), conf=_Tensor(conf),
                                                 cls=_Tensor(cls)))


def test_ultralytics_result_stand_in_and_any_callable_feed_the_same_detections() -> None:
    res = _ultralytics_result([[0, 0, 10, 20], [5, 5, 25, 45]], [0.8, 0.6], [0, 2])
    d = from_ultralytics(res, 3, classes=[0])
    np.testing.assert_allclose(d.tlwh, [[0, 0, 10, 20]])
    det = CallableDetector(lambda frame: [res], classes=[0, 2], min_score=0.7)
    out = det(np.zeros((50, 50, 3), np.uint8))
    assert len(out) == 1 and out.frame == 0
    arr = CallableDetector(lambda frame: np.array([[1, 2, 11, 22, 0.5]]))
    np.testing.assert_allclose(arr(None, 4).tlwh, [[1, 2, 10, 20]])
    pair = CallableDetector(lambda frame: (np.array([[1, 2, 11, 22]]), np.array([0.3])))
    assert pair(None).score.tolist() == [0.3]
    same = CallableDetector(lambda frame: Detections.from_tlwh(9, [[0, 0, 4, 4]]))
    assert same(None, 2).frame == 2
    with pytest.raises(ValueError, match="x2 >= x1"):
        CallableDetector(lambda frame: np.array([[10, 0, 0, 5]]))(None)
    with pytest.raises(ValueError, match=r"\(M, 4\) or \(M, 5\)"):
        CallableDetector(lambda frame: np.zeros((2, 3)))(None)
    with pytest.raises(TypeError, match="callable"):
        CallableDetector(3)  # type: ignore[arg-type]


# ---------------------------------------------------------------- HOG


@pytest.mark.shared
def test_hog_verifier_scores_a_real_person_above_the_pavement_beside_them(shared_dir: Path):
    from mvtrack.detection.hog import HOGDetector, hog_scores

    seq = shared_dir / "data" / "real" / "KITTI-17"
    frame = cv2.imread(str(seq / "img1" / "000120.jpg"))
    person = [860, 153, 57, 134]  # ground truth of ID 9 in frame 120
    pavement = [1000, 180, 57, 134]
    s = hog_scores(frame, np.array([person, pavement], float))
    assert s[0] > 0 > s[1], s
    dets = HOGDetector()(cv2.resize(frame, None, fx=0.5, fy=0.5), 5)
    assert dets.frame == 5 and dets.score.shape == (len(dets),)


def test_hog_by_name_takes_its_own_settings_and_the_pipelines_blob_defaults() -> None:
    from mvtrack.detection import make_detector
    from mvtrack.detection.hog import HOGDetector

    det = make_detector("hog", scale=1.1, min_area=236.0, close_size=7)
    assert isinstance(det, HOGDetector) and (det.scale, det.min_area) == (1.1, 236.0)
    with pytest.raises(ValueError, match="open_size"):  # a blob-stage setting HOG has not
        make_detector("hog", open_size=3)
    with pytest.raises(ValueError, match="min_area"):
        make_detector("hog", min_area=-1)


@pytest.mark.shared
def test_mvtrack_track_with_the_hog_detector_boxes_the_people_of_kitti17(
    shared_dir: Path, tmp_path: Path
) -> None:
    """``mvtrack track --detector hog`` on ten real frames: rows on the annotated people."""
    import shutil

    from mvtrack.cli import main
    from mvtrack.eval import iou_matrix
    from mvtrack.io.mot import read_tracks

    seq = shared_dir / "data" / "real" / "KITTI-17"
    folder = tmp_path / "img1"
    folder.mkdir()
    first = 91
    for k in range(first, first + 10):
        shutil.copy(seq / "img1" / f"{k:06d}.jpg", folder)
    out = tmp_path / "out"
    assert main(["track", str(folder), "--out", str(out), "--fps", "10", "--detector", "hog",
                 "--no-video"]) == 0
    rows = np.loadtxt(out / "results.txt", delimiter=",", ndmin=2)
    gt = read_tracks(seq / "gt.txt", "gt")
    hits = 0
    for f in np.unique(rows[:, 0]).astype(int):
        truth = gt.tlwh[(gt.frame == f + first - 2) & (gt.conf > 0)]
        iou = iou_matrix(rows[rows[:, 0] == f, 2:6], truth)
        hits += int((iou.max(axis=1) >= 0.5).sum()) if iou.size else 0
    # HOG's boxes are the detector's loose windows (KITTI-17 precision about 0.5 at IoU 0.5);
    # the disturbance map, starting cold on these frames, matches next to none
    assert hits >= 10 and hits >= 0.3 * len(rows), (hits, len(rows))


@pytest.mark.parametrize("compiled", [True, False])
def test_box_overlaps_are_numpys_broadcast_statement(compiled: bool) -> None:
    """The compiled intersection areas (and the plain function) equal the broadcast NumPy
    statement bit for bit, NaN boxes included."""
    from mvtrack.detection import splitmerge

    fn = splitmerge.overlap_areas if compiled else splitmerge.overlap_areas.py_func
    rng = np.random.default_rng(5)
    a = np.column_stack([rng.uniform(-20, 80, (40, 2)), rng.uniform(0, 30, (40, 2))])
    b = np.column_stack([rng.uniform(-20, 80, (25, 2)), rng.uniform(0, 30, (25, 2))])
    a[3, 1] = np.nan
    b[7, 2] = np.nan
    lo = np.maximum(a[:, None, :2], b[None, :, :2])
    hi = np.minimum(a[:, None, :2] + a[:, None, 2:], b[None, :, :2] + b[None, :, 2:])
    want = np.clip(hi - lo, 0.0, None).prod(axis=2)
    got = np.empty((40, 25))
    fn(a, b, got)
    np.testing.assert_array_equal(got, want)
    assert np.isnan(got[3]).all() and np.isnan(got[:, 7]).all() and (got == 0).any()
    assert (got > 0).sum() > 20
