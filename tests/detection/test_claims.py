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
