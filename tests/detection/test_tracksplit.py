"""Any blob front end with the tracker's predicted boxes (``track_split``): two vehicles whose
blobs merged are given one box each; without predictions the blobs are as the front end found
them; the option is refused where it cannot apply."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection import make_detector
from mvtrack.detection.splitmerge import PLAIN, SPLIT
from mvtrack.detection.tracksplit import TrackSplit
from mvtrack.types import TrackFrame, TrackState


def _frames() -> list[np.ndarray]:
    """Grey road; from frame 1 two bright 16×10 boxes bumper to bumper (one blob)."""
    empty = np.full((80, 120, 3), 60, np.uint8)
    cars = empty.copy()
    cars[35:45, 30:46] = 220  # car A: centre (37.5, 39.5)
    cars[35:45, 46:62] = 200  # car B right behind it: centre (53.5, 39.5)
    return [empty, cars]


def _tracks(xy: np.ndarray) -> TrackFrame:
    k = len(xy)
    return TrackFrame(0, np.arange(1, k + 1), np.full(k, int(TrackState.STOPPED)),
                      np.full(k, -1), xy, xy, xy, np.full((k, 2), [16.0, 10.0]),
                      np.zeros((k, 2)))


def test_a_blob_holding_two_predicted_cars_gives_one_box_each() -> None:
    empty, cars = _frames()
    plain = make_detector("frame-diff", close_size=0, min_area=10.0)
    plain(empty)
    (blob,) = plain(cars).tlwh  # the two cars are one blob: 32 px wide
    assert blob[2] == pytest.approx(32, abs=1)

    split = make_detector("frame-diff", close_size=0, min_area=10.0, track_split=True)
    assert isinstance(split, TrackSplit)
    split(empty)
    split.observe(None, _tracks(np.array([[37.5, 39.5], [53.5, 39.5]])))
    dets = split(cars)
    assert len(dets) == 2 and (split.flags == SPLIT).all()
    order = np.argsort(dets.xy[:, 0])
    np.testing.assert_allclose(dets.xy[order], [[37.5, 39.5], [53.5, 39.5]], atol=1.0)
    np.testing.assert_allclose(dets.wh[order], [[16, 10], [16, 10]], atol=1.5)


def test_without_predicted_boxes_the_blobs_are_unchanged() -> None:
    empty, cars = _frames()
    a = make_detector("frame-diff", close_size=0, min_area=10.0)
    b = make_detector("frame-diff", close_size=0, min_area=10.0, track_split=True)
    a(empty)
    b(empty)
    da, db = a(cars), b(cars)
    np.testing.assert_array_equal(da.xy, db.xy)
    np.testing.assert_array_equal(da.area, db.area)
    assert (b.flags == PLAIN).all() and b.mask is not None  # the front end's own mask


def test_one_predicted_car_in_the_blob_leaves_it_whole() -> None:
    empty, cars = _frames()
    d = make_detector("frame-diff", close_size=0, min_area=10.0, track_split=True)
    d(empty)
    d.observe(None, _tracks(np.array([[37.5, 39.5]])))
    (box,) = d(cars).tlwh
    assert box[2] == pytest.approx(32, abs=1) and (d.flags == PLAIN).all()


def _fragments() -> list[np.ndarray]:
    """Grey road; from frame 1 one 16×10 car in two tones 3 px apart (two blobs)."""
    empty = np.full((80, 120, 3), 60, np.uint8)
    car = empty.copy()
    car[35:45, 30:37] = 220
    car[35:45, 40:46] = 200
    return [empty, car]


@pytest.mark.parametrize("merge", [True, False])
def test_track_merge_joins_the_fragments_in_one_predicted_box_or_leaves_them(merge) -> None:
    empty, car = _fragments()
    d = make_detector("frame-diff", close_size=0, min_area=10.0, track_split=True,
                      track_merge=merge)
    d(empty)
    d.observe(None, _tracks(np.array([[37.5, 39.5]])))
    dets = d(car)
    if merge:  # one box, the union of the fragments
        assert len(dets) == 1 and dets.tlwh[0][2] == pytest.approx(16, abs=1)
    else:  # the two fragments as they were
        assert len(dets) == 2 and (d.flags == PLAIN).all()


def test_without_merging_a_blob_of_two_cars_is_still_divided() -> None:
    empty, cars = _frames()
    d = make_detector("frame-diff", close_size=0, min_area=10.0, track_split=True,
                      track_merge=False)
    d(empty)
    d.observe(None, _tracks(np.array([[37.5, 39.5], [53.5, 39.5]])))
    dets = d(cars)
    assert len(dets) == 2 and (d.flags == SPLIT).all()


@pytest.mark.parametrize("params, words", [
    ({"track_split": "yes"}, "track_split must be true or false"),
    ({"track_split": True, "track_merge": 1}, "track_merge must be true or false"),
])
def test_bad_track_split_values_are_refused(params, words) -> None:
    with pytest.raises(ValueError, match=words):
        make_detector("disturbance-map", **params)


def test_track_split_needs_a_blob_front_end() -> None:
    with pytest.raises(ValueError, match="background-model front end"):
        make_detector("hog", track_split=True)
