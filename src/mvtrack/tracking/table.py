"""The tracker's state as columns: :class:`TrackTable` (one row per live track) and the
row operations on it and on the predictor's batch state.

The predictor state is kept beside the table, row-aligned with it; :func:`take_state`,
:func:`put_state` and :func:`concat_state` apply the table's row operations to it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.filters.cv import CVState
from mvtrack.types import Detections, concat_rows, take_rows

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: integer columns of :class:`TrackTable`
UID, TID, STATE, HITS, MISSES, AGE, LAST_K, PREV_K = range(8)
N_INT = 8
#: float columns: last measurement (x, y), the one before (x, y), box (w, h)
LAST_XY, PREV_XY, WH = slice(0, 2), slice(2, 4), slice(4, 6)
N_FLOAT = 6
#: the float columns of a new track from its detection's ``x, y, w, h``
BIRTH_COLS = np.array([0, 1, 0, 1, 2, 3])


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
    floats : (N, 6) float64
        ``last_xy (2), prev_xy (2), wh (2)``.
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


def take_state(state: Any, idx: NDArray[np.intp] | slice) -> Any:
    """Rows ``idx`` of the predictor's batch ``state`` (views for a slice of a closed-form
    state)."""
    if type(state) is CVState:
        if isinstance(idx, slice):
            return CVState(state.x[idx], state.P[idx])
        return CVState(state.x.take(idx, 0), state.P.take(idx, 0))
    return take_rows(state, idx)


def kept_rows(delete: BoolArray) -> NDArray[np.intp] | slice:
    """The rows not in ``delete``: a slice when they are the first ones (only the last rows
    end, as when last frame's false alarms end), else their indices."""
    keep = (~delete).nonzero()[0]
    if keep.size == 0 or keep[-1] == keep.size - 1:
        return slice(0, keep.size)
    return keep


def uid_ramp(b: int) -> IntArray:
    """(b, 8) int64: 0, 1, ..., b − 1 in the uid column, 0 elsewhere (added to a birth row)."""
    ramp = np.zeros((b, N_INT), dtype=np.int64)
    ramp[:, UID] = np.arange(b)
    return ramp


def detection_rows(dets: Detections) -> FloatArray:
    """(M + 1, 4): each detection's ``x, y, w, h``, then a row of NaN (the one index −1 takes,
    so that one ``take`` by a track's detection index also fills the tracks without one)."""
    m = dets.xy.shape[0]
    rows = np.empty((m + 1, 4))
    rows[:m, :2] = dets.xy
    rows[:m, 2:] = dets.wh
    rows[m] = np.nan
    return rows


def put_state(state: Any, idx: NDArray[np.intp], new: Any) -> Any:
    """A copy of the batch ``state`` with rows ``idx`` replaced by the rows of ``new``."""
    changes = {}
    for f in dataclasses.fields(state):
        a = getattr(state, f.name)
        if isinstance(a, np.ndarray) and a.ndim >= 1:
            a = a.copy()
            a[idx] = getattr(new, f.name)
            changes[f.name] = a
    return dataclasses.replace(state, **changes)


def concat_state(a: Any, b: Any) -> Any:
    """The rows of batch state ``a``, then those of ``b``."""
    if type(a) is CVState:
        return CVState(np.concatenate([a.x, b.x]), np.concatenate([a.P, b.P]))
    return concat_rows(a, b)

