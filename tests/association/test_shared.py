"""A weak box over another track's predicted box: the test, its noise, and the tracker's use."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.association.assign import HIGH, LOW
from mvtrack.association.shared import OFF, measurement_var, shared, shared_std
from mvtrack.eval.iou import iou_matrix
from mvtrack.tracking import Tracker, TrackerConfig
from mvtrack.types import Detections

WH = np.array([[40.0, 80.0], [40.0, 80.0]])
T = 0.4  # TrackerConfig().shared_iou


def _shared(second_x: float, dclass: int, det_index=(0, -1), t: float = T) -> list[bool]:
    centre = np.array([[100.0, 100.0], [second_x, 100.0]])
    dxy, dwh = np.array([[110.0, 100.0]]), np.array([[40.0, 80.0]])
    return shared(np.array(det_index, np.intp), centre, WH, dxy, dwh,
                  np.array([dclass], np.int8), t).tolist()


def test_a_weak_box_over_a_neighbours_prediction_is_shared():
    # the neighbour at x = 120 is 10 px = 0.25 widths from the box: IoU 0.75 / 1.25 = 0.6
    assert _shared(120.0, LOW) == [True, False]
    assert _shared(120.0, HIGH) == [False, False]  # a strong box is the detector's sure one
    # 30 px = 0.75 widths away: IoU 0.25 / 1.75 = 0.14, under the threshold
    assert _shared(140.0, LOW, t=0.1) == [True, False]
    assert _shared(140.0, LOW) == [False, False]
    # the track's own predicted box does not count, nor does a track without a box
    assert _shared(120.0, LOW, det_index=(-1, 0)) == [False, True]
    assert _shared(120.0, LOW, det_index=(-1, -1)) == [False, False]
    assert _shared(120.0, LOW, t=OFF) == [False, False]  # shared_iou None: off


def test_the_shared_std_is_the_offset_of_two_boxes_overlapping_by_the_threshold():
    for t in (0.2, T, 0.7):
        d = shared_std(t) * 40.0  # in pixels, along x
        a, b = np.array([[0.0, 0.0, 40.0, 80.0]]), np.array([[d, 0.0, 40.0, 80.0]])
        assert iou_matrix(a, b)[0, 0] == pytest.approx(t, abs=1e-12)
    assert shared_std(OFF) == 0.0


def test_measurement_var_widens_only_the_shared_rows():
    r = measurement_var(0.1, WH, np.array([True, False]), T)
    d = 0.6 / 1.4  # (1 - t) / (1 + t) box sizes
    np.testing.assert_allclose(r, [[(d * 40) ** 2, (d * 80) ** 2], [16.0, 64.0]])
    # a measurement noise already wider than the shared std is kept
    np.testing.assert_allclose(measurement_var(0.6, WH, np.array([True, False]), T),
                               (0.6 * WH) ** 2)


def _gain(weak: bool, neighbour: bool, fused: bool, t: float | None = T) -> float:
    """How far the walker's track moves towards a box 6 px off its prediction in frame 27,
    as a share of the innovation along x; a neighbour stands 9 px ahead (IoU 0.54)."""
    config = TrackerConfig(fps=30.0, score_scale="prob", score_high=0.5, shared_iou=t)
    tracker = Tracker(config, fused=fused)
    for k in range(28):
        xy = [[100.0 + 3.0 * k, 200.0]] + ([[190.0, 200.0]] if neighbour else [])
        score = [0.9] + ([0.9] if neighbour else [])
        if k == 27:
            xy[0][0] += 6.0
            score[0] = 0.2 if weak else 0.9
        tf = tracker.step(Detections(k, np.array(xy), np.tile([30.0, 80.0], (len(xy), 1)),
                                     np.array(score)))
    row = int(np.flatnonzero(tf.det_index == 0)[0])
    innovation = tf.measured_xy[row, 0] - tf.predicted_xy[row, 0]
    return float((tf.filtered_xy[row, 0] - tf.predicted_xy[row, 0]) / innovation)


@pytest.mark.parametrize("fused", [True, False])
def test_a_shared_weak_box_moves_its_track_less(fused):
    strong, weak = _gain(False, True, fused), _gain(True, True, fused)
    assert 0.0 < weak < 0.5 * strong
    # without the neighbour a weak box moves the track as far as a strong one
    assert _gain(True, False, fused) == pytest.approx(_gain(False, False, fused), rel=1e-9)
    # with the rule off the shared weak box moves it as far as a strong one
    assert _gain(True, True, fused, None) == pytest.approx(strong, rel=1e-9)
    # the compiled step and the array step agree
    assert weak == pytest.approx(_gain(True, True, not fused), rel=1e-9)
