"""The track table and the row operations on the predictors' batch states."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.filters.cv import KalmanCVPredictor
from mvtrack.filters.predictors import make_predictor
from mvtrack.tracking import table as tr
from mvtrack.types import n_rows


def test_table_columns_by_name() -> None:
    rng = np.random.default_rng(0)
    tab = tr.TrackTable(rng.integers(0, 9, (7, tr.N_INT)), rng.normal(size=(7, tr.N_FLOAT)))
    np.testing.assert_array_equal(tab.uid, tab.ints[:, 0])
    np.testing.assert_array_equal(tab.wh, tab.floats[:, 4:6])
    np.testing.assert_array_equal(tab.last_xy, tab.floats[:, 0:2])
    np.testing.assert_array_equal(tab.score, tab.floats[:, 6])
    assert len(tab.take(np.array([1, 4]))) == 2 and len(tr.TrackTable.empty()) == 0


@pytest.mark.parametrize("name", ["kalman-imm", "kalman-cv", "kalman-ca", "rls", "structured"])
def test_take_and_concat_of_every_predictors_state(name: str) -> None:
    rng = np.random.default_rng(1)
    pred = make_predictor(name)
    state = pred.predict(pred.init(rng.uniform(0, 100, (7, 2))))
    a, b = tr.take_state(state, slice(0, 4)), tr.take_state(state, np.arange(4))
    assert type(a) is type(state) and n_rows(a) == n_rows(b) == 4
    np.testing.assert_array_equal(pred.position(a), pred.position(b))
    both = tr.concat_state(a, tr.take_state(state, np.arange(4, 7)))
    np.testing.assert_array_equal(pred.position(both), pred.position(state))


def test_the_closed_form_state_slices_are_views() -> None:
    state = KalmanCVPredictor().init(np.zeros((5, 2)))
    a = tr.take_state(state, slice(0, 3))
    assert np.shares_memory(a.x, state.x)


def test_many_births_in_one_frame_get_consecutive_uids() -> None:
    from mvtrack.tracking import Tracker
    from mvtrack.types import Detections

    rng = np.random.default_rng(2)
    tracker = Tracker()
    tracker.step(Detections(0, rng.uniform(0, 1000, (40, 2)), np.full((40, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40))
    tracker.step(Detections(1, rng.uniform(2000, 3000, (50, 2)), np.full((50, 2), 10.0)))
    np.testing.assert_array_equal(np.sort(tracker.tracks.uid), np.arange(40, 90))
    assert (tracker.tracks.last_k == 1).all() and (tracker.tracks.prev_k == 1).all()
    assert (tracker.tracks.hits == 1).all() and (tracker.tracks.track_id == -1).all()
