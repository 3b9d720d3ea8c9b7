"""The track life cycle as pure functions over the arrays of all tracks.

States (:class:`~mvtrack.types.TrackState`)::

    birth ──> TENTATIVE ──(confirm_hits associations within confirm_window)──> CONFIRMED
                 │                                                   │  ▲        │
                 └─(missed > tentative_max_misses, or window over)─> ✗  │ det    │ no det
                                                                     ▼  │        ▼
                           STOPPED <──(held by template matching)── COASTING ──(misses >
                                                                                max_misses)──> ✗

A confirmed track that gets a detection is ``CONFIRMED``; one that gets none is ``COASTING``
(its predicted box is output and flagged), unless the video pipeline's template matching
(``rescue``) finds it, in which case it is ``STOPPED`` (kept alive with the same ID). A
``STOPPED`` or ``COASTING`` track that gets a detection again is ``CONFIRMED``. Deleted tracks
(✗) leave the table and are never output. New tracks start from unassigned detections
(new-target recognition, step 4 of SPEC §2.1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.tracking.config import FrameParams
from mvtrack.tracking.table import AGE, HITS, MISSES, STATE, TID  # columns of TrackTable.ints
from mvtrack.types import TrackState

IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

TENTATIVE = int(TrackState.TENTATIVE)
CONFIRMED = int(TrackState.CONFIRMED)
COASTING = int(TrackState.COASTING)
STOPPED = int(TrackState.STOPPED)


#: what one frame adds to every row: misses and age + 1
_COUNTER_STEP = np.zeros(8, dtype=np.int64)
_COUNTER_STEP[[MISSES, AGE]] = 1


def count_hits(ints: IntArray, matched: BoolArray, held: BoolArray | IntArray) -> None:
    """Advance the counters of every track by one frame, in place.

    ``hits`` counts associations with a detection (``matched``); ``misses`` counts
    consecutive frames without a detection or template match (``held``: a mask of the tracks
    that got either, or their row indices); ``age`` counts frames since birth.
    """
    ints[:, HITS] += matched
    ints += _COUNTER_STEP  # misses and age + 1 (one add over the whole block)
    if held.dtype == np.bool_:
        np.copyto(ints[:, MISSES], 0, where=held)  # cheaper than a masked assignment
    else:
        ints[held, MISSES] = 0


def next_state(
    ints: IntArray, matched: BoolArray, rescued: BoolArray | None, fp: FrameParams
) -> tuple[IntArray, BoolArray, BoolArray]:
    """States after one frame, which tracks end, and which were confirmed just now.

    Parameters
    ----------
    ints : (N, 8) int
        The table's integer block with the counters already advanced (:func:`count_hits`)
        and ``state`` still the previous frame's.
    matched : (N,) bool
        Got a detection this frame.
    rescued : (N,) bool or None
        Found by template matching this frame (never together with ``matched``).
    fp : FrameParams
        Life-cycle parameters in frames.

    Returns
    -------
    state : (N,) int
        New states: tentative tracks stay ``TENTATIVE`` until confirmed; the others are
        ``CONFIRMED`` (detection), ``STOPPED`` (template match) or ``COASTING`` (neither).
    delete : (N,) bool
        Tracks that end this frame: tentative ones after more than ``tentative_max_misses``
        consecutive misses or at the end of the confirmation window, the others after more
        than ``max_misses`` consecutive misses.
    confirmed_now : (N,) bool
        Tentative tracks confirmed this frame (they get public IDs).
    """
    misses, age = ints[:, MISSES], ints[:, AGE]
    tentative = ints[:, STATE] == TENTATIVE
    confirmed_now = tentative & (ints[:, HITS] >= fp.confirm_hits) & (age <= fp.confirm_window)
    still = tentative ^ confirmed_now
    state = COASTING - matched  # CONFIRMED (= COASTING − 1) where matched
    if rescued is not None:
        state[rescued] = STOPPED
    np.copyto(state, TENTATIVE, where=still)
    delete = np.where(
        still,
        (misses > fp.tentative_max_misses) | (age >= fp.confirm_window),
        misses > fp.max_misses,
    )
    return state, delete, confirmed_now


def hand_out_ids(ints: IntArray, confirmed_now: BoolArray, next_id: int) -> int:
    """Give the tracks confirmed this frame consecutive public IDs from ``next_id``, in place.

    Tracks confirmed in the same frame are numbered in order of their internal uid (birth
    order), so IDs stay consecutive and do not depend on the order of the detections. Returns
    the next free ID.
    """
    idx = confirmed_now.nonzero()[0]  # rows are kept in uid order
    ints[idx, TID] = np.arange(next_id, next_id + idx.size)
    return next_id + int(idx.size)


def birth_order(xy: NDArray[np.float64]) -> IntArray:
    """Order in which new tracks are created from unassigned detections at ``xy`` (K, 2).

    Sorted by (x, y) so that internal uids, and through them public IDs, do not depend on
    the order of the rows in the detection file.
    """
    return np.lexsort((xy[:, 1], xy[:, 0]))
