"""The tracker's state as columns: :class:`TrackTable` (one row per live track) and the
row operations on it and on the predictor's batch state.

The predictor state is kept beside the table, row-aligned with it; :func:`take_state`,
:func:`put_state` and :func:`concat_state` apply the table's row operations to it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.filters.cv import CVState
from mvtrack.tracking.lifecycle import (
    AGE,
    HITS,
    LAST_K,
    LAST_X,
    LAST_Y,
    MISSES,
    N_FLOAT,
    N_INT,
    PREV_K,
    PREV_X,
    PREV_Y,
    SCORE,
    STATE,
    TID,
    UID,
    H,
    W,
)
from mvtrack.types import concat_rows, take_rows

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: the columns are the life cycle's (its kernels read them): :mod:`mvtrack.tracking.lifecycle`
LAST_XY, PREV_XY, WH = slice(LAST_X, LAST_Y + 1), slice(PREV_X, PREV_Y + 1), slice(W, H + 1)


@dataclass(frozen=True)
class TrackTable:
    """The ``N`` live tracks as a struct of arrays (the predictor state is kept beside it).

    The columns are stored in two blocks, one ``int64`` and one ``float64``, so that growing
    and shrinking the table costs two array operations (``types.take_rows`` / ``concat_rows``
    work on it too); the properties give each column by name.

    Attributes
    ----------
    ints : (N, 8) int64
        ``uid, track_id, state, hits, misses, age, last_k, prev_k``.
    floats : (N, 7) float64
        ``last_xy (2), prev_xy (2), wh (2), score`` (the sum of the calibrated scores of the
        track's detections).
    """

    ints: IntArray
    floats: FloatArray

    def __len__(self) -> int:
        return int(self.ints.shape[0])

    @classmethod
    def empty(cls) -> TrackTable:
        """No tracks."""
        return cls(np.zeros((0, N_INT), dtype=np.int64), np.zeros((0, N_FLOAT)))

    def take(self, idx: NDArray[np.intp] | slice) -> TrackTable:
        """Rows ``idx`` (row indices, or a slice: views)."""
        if isinstance(idx, slice):
            return TrackTable(self.ints[idx], self.floats[idx])
        return TrackTable(self.ints.take(idx, 0), self.floats.take(idx, 0))

    @property
    def uid(self) -> IntArray:
        """(N,) internal identity, unique for the tracker's life, given at birth."""
        return self.ints[:, UID]

    @property
    def track_id(self) -> IntArray:
        """(N,) public ID (consecutive from 1 in order of confirmation), −1 while tentative."""
        return self.ints[:, TID]

    @property
    def state(self) -> IntArray:
        """(N,) :class:`~mvtrack.types.TrackState` after the last frame."""
        return self.ints[:, STATE]

    @property
    def hits(self) -> IntArray:
        """(N,) associations with a detection (the birth detection counts)."""
        return self.ints[:, HITS]

    @property
    def misses(self) -> IntArray:
        """(N,) consecutive frames without a detection or template match."""
        return self.ints[:, MISSES]

    @property
    def age(self) -> IntArray:
        """(N,) frames since birth (1 in the birth frame)."""
        return self.ints[:, AGE]

    @property
    def last_k(self) -> IntArray:
        """(N,) step number of the last measurement."""
        return self.ints[:, LAST_K]

    @property
    def prev_k(self) -> IntArray:
        """(N,) step number of the measurement before it (= last_k after one)."""
        return self.ints[:, PREV_K]

    @property
    def last_xy(self) -> FloatArray:
        """(N, 2) last measurement."""
        return self.floats[:, LAST_XY]

    @property
    def prev_xy(self) -> FloatArray:
        """(N, 2) the measurement before the last (= last after one)."""
        return self.floats[:, PREV_XY]

    @property
    def wh(self) -> FloatArray:
        """(N, 2) box size, exponentially smoothed over the associated detections."""
        return self.floats[:, WH]

    @property
    def score(self) -> FloatArray:
        """(N,) sum of the calibrated scores of the track's detections."""
        return self.floats[:, SCORE]


def take_state(state: Any, idx: NDArray[np.intp] | slice) -> Any:
    """Rows ``idx`` of the predictor's batch ``state`` (views for a slice of a closed-form
    state)."""
    if type(state) is CVState:
        if isinstance(idx, slice):
            return CVState(state.x[idx], state.P[idx])
        return CVState(state.x.take(idx, 0), state.P.take(idx, 0))
    return take_rows(state, idx)


def concat_state(a: Any, b: Any) -> Any:
    """The rows of batch state ``a``, then those of ``b``."""
    if type(a) is CVState:
        return CVState(np.concatenate([a.x, b.x]), np.concatenate([a.P, b.P]))
    return concat_rows(a, b)

