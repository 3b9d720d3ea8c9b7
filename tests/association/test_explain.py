"""The explain facility names the nearest track, its distance and the gate it missed."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association import Gate, TrackView, assign, distance_matrix
from mvtrack.association.explain import explain


def _frame() -> tuple[TrackView, np.ndarray]:
    view = TrackView.from_arrays([[0.0, 0.0], [100.0, 0.0], [300.0, 0.0]], cov=4.0)
    # d0 near track 0; d1 25 px from track 1 (outside a 20 px gate); d2 between 0 and 1 but
    # nearer track 0 which took d0 under the exclusive rules; no detection near track 2
    dets = np.array([[1.0, 0.0], [125.0, 0.0], [8.0, 6.0]])
    return view, dets


def test_unassociated_detection_reports_nearest_track_value_and_gate() -> None:
    view, dets = _frame()
    ex = explain(view, dets, "euclidean", 400.0, rule="optimal")
    assert ex.det.tolist() == [1, 2]
    assert ex.det_track.tolist() == [1, 0]
    np.testing.assert_allclose(ex.det_value, [625.0, 100.0])
    assert ex.gate == 400.0
    assert ex.det_reason[0] == "outside gate: 625 > 400"
    assert ex.det_reason[1].startswith("inside a gate")
    # tracks left without a detection: 1 (d1 too far) and 2
    assert ex.track.tolist() == [1, 2]
    assert ex.track_det.tolist() == [1, 1]
    np.testing.assert_allclose(ex.track_value, [625.0, 175.0**2])
    text = ex.table()
    assert "outside gate" in text and "distance euclidean" in text


def test_nearest_rule_leaves_the_shared_detection_unused() -> None:
    view, dets = _frame()
    ex = explain(view, dets, "euclidean", 400.0, rule="nearest")
    assert ex.det.tolist() == [1, 2]  # track 0 took d0 (nearest); nobody took d2


def test_explain_given_detection_and_mahalanobis_values() -> None:
    view, dets = _frame()
    ti, dj, c = Gate.build("mahalanobis", view, 9.21).pairs(dets, np.ones_like(dets))
    a = assign(ti, dj, c, 3, 3, "greedy")
    ex = explain(view, dets, "mahalanobis", assignment=a, det=[0, 1])
    assert ex.det_assigned_track.tolist() == [0, -1]
    assert ex.det_reason[0] == "associated with track 0"
    d = distance_matrix("mahalanobis", view, dets)
    np.testing.assert_allclose(ex.det_value, d[:, [0, 1]].min(axis=0))
    assert ex.gate == 9.21


def test_explain_without_tracks_and_bad_rows() -> None:
    empty = TrackView.from_arrays(np.zeros((0, 2)))
    ex = explain(empty, np.array([[1.0, 2.0]]))
    assert ex.det_track.tolist() == [-1] and np.isinf(ex.det_value[0])
    assert ex.det_reason == ["no tracks"]
    view, dets = _frame()
    with pytest.raises(ValueError, match="detection row out of range"):
        explain(view, dets, det=[5])
