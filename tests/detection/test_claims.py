"""The compiled test of a blob claimed by two predicted boxes
(:func:`mvtrack.detection.claims.shared_blob`) against the array computation it replaces
(:func:`~mvtrack.detection.splitmerge.usable_predictions` and
:func:`~mvtrack.detection.splitmerge.blob_claims`)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.detection import claims
from mvtrack.detection.splitmerge import blob_claims, usable_predictions


def _reference(xy, wh, predicted, cover):  # type: ignore[no-untyped-def]
    pred = usable_predictions(predicted)
    if len(pred) < 2 or len(xy) == 0:
        return False, pred
    boxes = np.hstack([xy - wh / 2, wh])
    home, claimed = blob_claims(boxes, pred, cover)
    return bool((np.bincount(home[claimed], minlength=len(boxes)) >= 2).any()), pred


def _case(rng: np.random.Generator, seed: int):  # type: ignore[no-untyped-def]
    m, n = int(rng.integers(0, 6)), int(rng.integers(0, 7))
    xy = rng.uniform(0, 40, (m, 2))
    wh = rng.uniform(2, 30, (m, 2))
    pred = np.hstack([rng.uniform(0, 40, (n, 2)), rng.uniform(1, 15, (n, 2))])
    if n and seed % 3 == 0:  # duplicates, equal areas, empty and non-finite boxes
        pred[rng.integers(0, n)] = pred[0]
        pred[rng.integers(0, n), 2] = 0.0
        pred[rng.integers(0, n), rng.integers(0, 4)] = np.nan
        pred[rng.integers(0, n), rng.integers(0, 4)] = np.inf
    if m and seed % 4 == 1:  # integer boxes: ties between blobs
        xy, wh = np.round(xy), np.round(wh)
        pred = np.round(pred)
    return xy, wh, np.ascontiguousarray(pred)


@pytest.mark.parametrize("compiled", [True, False])
def test_shared_blob_matches_blob_claims(compiled: bool) -> None:
    shared = claims.shared_blob if compiled else claims.shared_blob.py_func
    usable = claims.usable_boxes if compiled else claims.usable_boxes.py_func
    rng = np.random.default_rng(7)
    hits = 0
    for seed in range(600):
        xy, wh, pred = _case(rng, seed)
        cover = float(rng.choice([0.3, 0.5, 0.8]))
        want, want_pred = _reference(xy, wh, pred, cover)
        np.testing.assert_array_equal(usable(pred), want_pred)
        assert bool(shared(xy, wh, pred, cover)) is want
        hits += want
    assert 20 < hits < 580  # both answers are exercised


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("seed", range(5))
def test_distinct_boxes_keeps_the_larger_of_two_that_share_half(seed, compiled) -> None:
    """Against the rule written with NumPy: a box is dropped when it shares ``same`` of its
    area with a larger box, or with an earlier box of the same area."""
    from mvtrack.detection.splitmerge import distinct_boxes

    fn = distinct_boxes if compiled else distinct_boxes.py_func
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 9))
    pred = np.column_stack([rng.uniform(0, 30, (n, 2)), rng.uniform(2, 20, (n, 2))])
    if n > 2:
        pred[1] = pred[0]  # equal areas: the earlier is kept
    area = pred[:, 2] * pred[:, 3]
    lo, hi = pred[:, :2], pred[:, :2] + pred[:, 2:]
    side = np.clip(np.minimum(hi[:, None], hi[None]) - np.maximum(lo[:, None], lo[None]), 0, None)
    share = side.prod(axis=2) / np.minimum(area[:, None], area[None])
    np.fill_diagonal(share, 0.0)
    order = np.arange(n)
    smaller = (area[:, None] < area[None]) | ((area[:, None] == area[None])
                                              & (order[:, None] > order[None]))
    want = pred[~((share >= 0.5) & smaller).any(axis=1)]
    np.testing.assert_array_equal(fn(np.ascontiguousarray(pred), 0.5), want)
