"""The track life cycle, all of it: births, confirmation, coasting, stopped, deletion, IDs.

States (:class:`~mvtrack.types.TrackState`)::

    birth ──> TENTATIVE ──(confirm_hits consecutive detections, scores summing to
                 │          confirm_score)──────────────────────────> CONFIRMED
                 └─(a frame without detection)─> ✗                   │  ▲        │
                                                                    det │  │ det    │ no det
                                                                     ▼  │        ▼
                           STOPPED <──(held by template matching)── COASTING ──(lost)──> ✗

Everything is counted in frames, the frames in which the detector could have seen the
object, and in what the filter knows, never in seconds:

- **birth** (:func:`births`): a detection that no track took, above ``min_score``, whose box
  overlaps no live track's box by ``birth_iou`` (a second box on an object already tracked
  starts nothing), starts a tentative track;
- **confirmation**: ``confirm_hits`` detections in consecutive frames whose calibrated scores
  (:mod:`mvtrack.tracking.scores`) sum to at least ``confirm_score`` — two strong boxes, or
  more of weaker ones, make a track; a tentative track dies at its first miss;
- **coasting and loss**: a confirmed track without detection coasts on its prediction. It
  lives through ``min_misses`` frames without detection whatever happens (a detector misses
  a few frames, however many seconds they last), then is **lost** (deleted) once its
  predicted position is uncertain by more than ``lost_std`` box sizes along either axis
  (``√P̄_xx > lost_std · w`` or ``√P̄_yy > lost_std · h``), when the filter could no longer
  tell it from a neighbour — soon for a fast or new object at a low frame rate, late for a
  steady one at a high rate — and at the latest after ``max_misses`` frames, or at once when
  its prediction leaves the image;
- **rows**: a coasting track's row is written while its prediction is certain to within
  ``coast_std`` box sizes; tentative rows only when asked (offline backfilling);
- **IDs**: public IDs are handed out at confirmation, in birth order.

:func:`advance` and :func:`births` are compiled kernels (:func:`mvtrack.jit.kernel`) over
the table's columns (:mod:`mvtrack.tracking.table`), which are defined here because the
kernels read them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.assign import NO_STAND
from mvtrack.jit import kernel
from mvtrack.types import TrackState

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

TENTATIVE = int(TrackState.TENTATIVE)
CONFIRMED = int(TrackState.CONFIRMED)
COASTING = int(TrackState.COASTING)
STOPPED = int(TrackState.STOPPED)

#: integer columns of the track table
UID, TID, STATE, HITS, MISSES, AGE, LAST_K, PREV_K = range(8)
N_INT = 8
#: float columns: last measurement (x, y), the one before (x, y), box (w, h), score sum
LAST_X, LAST_Y, PREV_X, PREV_Y, W, H, SCORE = range(7)
N_FLOAT = 7

#: life-cycle parameters as :func:`advance` reads them (:meth:`TrackerConfig.life_cycle`)
(P_CONFIRM_HITS, P_CONFIRM_SCORE, P_MAX_MISSES, P_LOST_STD, P_COAST_STD, P_SMOOTHING,
 P_TENTATIVE_ROWS, P_FRAME_W, P_FRAME_H, P_BIRTH_IOU, P_FPS, P_MIN_MISSES) = range(12)
N_PARAMS = 12


@kernel
def advance(ints: IntArray, floats: FloatArray, det_index: NDArray[np.intp],
            rescued: BoolArray, z: FloatArray, zwh: FloatArray, zscore: FloatArray,
            std: FloatArray, centre: FloatArray, k: int, p: FloatArray
            ) -> tuple[BoolArray, BoolArray, BoolArray]:
    """One frame of the life cycle of ``N`` tracks, the table updated in place.

    Parameters
    ----------
    ints, floats : (N, 8), (N, 7)
        The table (columns above), states of the previous frame.
    det_index : (N,) intp
        Each track's detection this frame (−1: none).
    rescued : (N,) bool
        Held by template matching (a stopped vehicle) instead.
    z, zwh, zscore : (N, 2), (N, 2), (N,)
        Each track's measured position, its detection's box size and calibrated score.
    std : (N, 2)
        Standard deviation of each track's predicted position along x and y.
    centre : (N, 2)
        Each track's predicted position (the end of a track that leaves the image).
    k : int
        The frame's index.
    p : (N_PARAMS,) float
        The parameters (``P_*``; a rule that is off is ``inf``, an image size unknown −1).

    Returns
    -------
    delete, confirmed_now, show : (N,) bool
        The tracks that end now, those confirmed now (to get IDs) and those with a row.
    """
    n = ints.shape[0]
    delete = np.zeros(n, np.bool_)
    confirmed_now = np.zeros(n, np.bool_)
    show = np.zeros(n, np.bool_)
    fw, fh = p[P_FRAME_W], p[P_FRAME_H]
    for i in range(n):
        matched = det_index[i] >= 0
        held = matched or rescued[i]
        ints[i, AGE] += 1
        if matched:
            ints[i, HITS] += 1
            floats[i, W] += p[P_SMOOTHING] * (zwh[i, 0] - floats[i, W])
            floats[i, H] += p[P_SMOOTHING] * (zwh[i, 1] - floats[i, H])
            floats[i, SCORE] += zscore[i]
        if held:
            ints[i, MISSES] = 0
            ints[i, PREV_K] = ints[i, LAST_K]
            ints[i, LAST_K] = k
            floats[i, PREV_X], floats[i, PREV_Y] = floats[i, LAST_X], floats[i, LAST_Y]
            floats[i, LAST_X], floats[i, LAST_Y] = z[i, 0], z[i, 1]
        else:
            ints[i, MISSES] += 1
        w, h = floats[i, W], floats[i, H]
        if ints[i, STATE] == TENTATIVE:
            if not matched:
                delete[i] = True  # a tentative track dies at its first miss
            elif (ints[i, HITS] >= p[P_CONFIRM_HITS]
                  and floats[i, SCORE] >= p[P_CONFIRM_SCORE]):
                ints[i, STATE] = CONFIRMED
                confirmed_now[i] = True
            show[i] = not delete[i] and (confirmed_now[i] or p[P_TENTATIVE_ROWS] > 0)
            continue
        if matched:
            ints[i, STATE] = CONFIRMED
        elif rescued[i]:
            ints[i, STATE] = STOPPED
        else:
            ints[i, STATE] = COASTING
            lost = ints[i, MISSES] > p[P_MAX_MISSES]
            lost |= ints[i, MISSES] > p[P_MIN_MISSES] and (
                std[i, 0] > p[P_LOST_STD] * w or std[i, 1] > p[P_LOST_STD] * h)
            if fw > 0:  # its prediction left the image: the object has left the view
                lost |= (centre[i, 0] < 0 or centre[i, 0] >= fw or centre[i, 1] < 0
                         or centre[i, 1] >= fh)
            delete[i] = lost
        show[i] = not delete[i] and (
            ints[i, STATE] != COASTING
            or (std[i, 0] <= p[P_COAST_STD] * w and std[i, 1] <= p[P_COAST_STD] * h)
        )
    return delete, confirmed_now, show


@kernel
def births(dxy: FloatArray, dwh: FloatArray, dclass: NDArray[np.int8],
           used: BoolArray, txy: FloatArray, twh: FloatArray, birth_iou: float
           ) -> NDArray[np.intp]:
    """The detections that start tentative tracks, in (x, y) order.

    Every detection not used by a track and not dropped (``dclass > 0``) whose box overlaps
    none of the boxes ``txy``, ``twh`` of the live tracks by an IoU of ``birth_iou`` or more
    (``inf``: no such test). The order makes internal uids, and through them public IDs,
    independent of the order of the rows in a detection file.
    """
    m, n = dxy.shape[0], txy.shape[0]
    keep = np.zeros(m, np.bool_)
    for j in range(m):
        if used[j] or dclass[j] == 0:
            continue
        ok = True
        if birth_iou <= 1.0:
            ax0, ax1 = dxy[j, 0] - 0.5 * dwh[j, 0], dxy[j, 0] + 0.5 * dwh[j, 0]
            ay0, ay1 = dxy[j, 1] - 0.5 * dwh[j, 1], dxy[j, 1] + 0.5 * dwh[j, 1]
            area = dwh[j, 0] * dwh[j, 1]
            for i in range(n):
                iw = (min(ax1, txy[i, 0] + 0.5 * twh[i, 0])
                      - max(ax0, txy[i, 0] - 0.5 * twh[i, 0]))
                ih = (min(ay1, txy[i, 1] + 0.5 * twh[i, 1])
                      - max(ay0, txy[i, 1] - 0.5 * twh[i, 1]))
                if iw <= 0.0 or ih <= 0.0:
                    continue
                inter = iw * ih
                if inter >= birth_iou * (area + twh[i, 0] * twh[i, 1] - inter):  # IoU ≥ t
                    ok = False
                    break
        keep[j] = ok
    idx = np.flatnonzero(keep)
    if idx.size > 1:
        key = np.empty(idx.size)
        order = np.argsort(dxy[idx, 1], kind="mergesort")
        idx = idx[order]
        key[:] = dxy[idx, 0]
        idx = idx[np.argsort(key, kind="mergesort")]
    return idx


def standing(ints: IntArray, floats: FloatArray) -> FloatArray:
    """The box ``(x, y, w, h)`` each track held by template matching in the last frame
    (state ``STOPPED``) stands in: its last position, where the template matched, and its
    box. (N, 4) with NaN rows for the other tracks; no rows when none is held
    (:data:`~mvtrack.association.assign.NO_STAND`). Such a track takes only a detection
    centred in it (:func:`~mvtrack.association.assign.standing_pairs`)."""
    held = ints[:, STATE] == STOPPED
    if not held.any():
        return NO_STAND
    out = np.full((ints.shape[0], 4), np.nan)
    out[held, :2] = floats[held, LAST_X:LAST_Y + 1]
    out[held, 2:] = floats[held, W:H + 1]
    return out


@kernel
def measurements(det_index: NDArray[np.intp], dxy: FloatArray, dwh: FloatArray,
                 cscore: FloatArray, found: BoolArray, found_xy: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray, BoolArray, BoolArray]:
    """Each track's measurement: its detection's centre, box and calibrated score, or the
    position template matching found (``found``, ``found_xy``, (N,) and (N, 2)); NaN (score 0)
    for none. Returns ``z``, ``zwh``, ``zscore``, ``rescued`` and ``held``."""
    n = det_index.shape[0]
    z = np.full((n, 2), np.nan)
    zwh = np.full((n, 2), np.nan)
    zscore = np.zeros(n)
    rescued = np.zeros(n, np.bool_)
    held = np.zeros(n, np.bool_)
    for i in range(n):
        j = det_index[i]
        if j >= 0:
            z[i, 0], z[i, 1] = dxy[j, 0], dxy[j, 1]
            zwh[i, 0], zwh[i, 1] = dwh[j, 0], dwh[j, 1]
            zscore[i] = cscore[j]
            held[i] = True
        elif found[i] and found_xy[i, 0] == found_xy[i, 0] and found_xy[i, 1] == found_xy[i, 1]:
            z[i, 0], z[i, 1] = found_xy[i, 0], found_xy[i, 1]
            rescued[i] = True
            held[i] = True
    return z, zwh, zscore, rescued, held


@kernel
def commit(ints: IntArray, floats: FloatArray, det_index: NDArray[np.intp],
           rescued: BoolArray, z: FloatArray, zwh: FloatArray, zscore: FloatArray,
           std: FloatArray, centre: FloatArray, pos: FloatArray, vel: FloatArray,
           dxy: FloatArray, dwh: FloatArray, dclass: NDArray[np.int8], cscore: FloatArray,
           k: int, p: FloatArray, next_id: int, next_uid: int):
    """The life cycle of one frame, after the filter's update: :func:`advance`, the IDs of the
    tracks confirmed now, the frame's rows, the tracks that live on and the new ones.

    ``pos``, ``vel`` (N, 2) are the tracks' estimates after the update; the rest as in
    :func:`advance` and :func:`births`. Returns

    - ``ints``, ``floats``: the next frame's table (the surviving rows, then the new tracks);
    - ``keep`` (intp): the surviving rows, ``new`` (intp): the detections that start tracks;
    - the frame's rows ``tid, state, det, measured (·, 2), filtered, predicted, wh, velocity,
      uid``: the shown tracks in table order, then the new tracks shown at once;
    - ``next_id``, ``next_uid``;
    - ``speed2`` (2,) and ``n_speed``: the sum of ``(v / box)²`` in (box sizes/s)² per axis
      over the confirmed tracks matched now, and their number (the scene's speeds).
    """
    n, m = ints.shape[0], dxy.shape[0]
    delete, confirmed_now, show = advance(ints, floats, det_index, rescued, z, zwh, zscore,
                                          std, centre, k, p)
    for i in range(n):  # IDs in birth order: rows are kept in uid order
        if confirmed_now[i]:
            ints[i, TID] = next_id
            next_id += 1
    speed2 = np.zeros(2)
    n_speed = 0
    fps = p[P_FPS]
    for i in range(n):
        if det_index[i] >= 0 and ints[i, STATE] == CONFIRMED:
            vx, vy = vel[i, 0] * fps / floats[i, W], vel[i, 1] * fps / floats[i, H]
            speed2[0] += vx * vx
            speed2[1] += vy * vy
            n_speed += 1
    keep = np.flatnonzero(~delete)
    used = np.zeros(m, np.bool_)
    for i in range(n):
        if det_index[i] >= 0:
            used[det_index[i]] = True
    kxy = np.empty((keep.size, 2))
    kwh = np.empty((keep.size, 2))
    for a in range(keep.size):
        i = keep[a]
        kxy[a, 0], kxy[a, 1] = pos[i, 0], pos[i, 1]
        kwh[a, 0], kwh[a, 1] = floats[i, W], floats[i, H]
    new = births(dxy, dwh, dclass, used, kxy, kwh, p[P_BIRTH_IOU])
    b = new.size
    ints2 = np.empty((keep.size + b, N_INT), np.int64)
    floats2 = np.empty((keep.size + b, N_FLOAT))
    for a in range(keep.size):
        ints2[a] = ints[keep[a]]
        floats2[a] = floats[keep[a]]
    born_shown = np.zeros(b, np.bool_)
    for e in range(b):
        j, a = new[e], keep.size + e
        ints2[a, UID] = next_uid + e
        ints2[a, TID] = -1
        ints2[a, STATE] = TENTATIVE
        ints2[a, HITS] = 1
        ints2[a, MISSES] = 0
        ints2[a, AGE] = 1
        ints2[a, LAST_K] = k
        ints2[a, PREV_K] = k
        floats2[a, LAST_X], floats2[a, LAST_Y] = dxy[j, 0], dxy[j, 1]
        floats2[a, PREV_X], floats2[a, PREV_Y] = dxy[j, 0], dxy[j, 1]
        floats2[a, W], floats2[a, H] = dwh[j, 0], dwh[j, 1]
        floats2[a, SCORE] = cscore[j]
        if p[P_CONFIRM_HITS] <= 1 and cscore[j] >= p[P_CONFIRM_SCORE]:
            ints2[a, STATE] = CONFIRMED
            ints2[a, TID] = next_id
            next_id += 1
        born_shown[e] = ints2[a, STATE] != TENTATIVE or p[P_TENTATIVE_ROWS] > 0
    next_uid += b
    rows = np.flatnonzero(show)
    nb = np.flatnonzero(born_shown)
    r = rows.size + nb.size
    tid = np.empty(r, np.int64)
    state = np.empty(r, np.int64)
    det = np.empty(r, np.int64)
    uid = np.empty(r, np.int64)
    measured = np.empty((r, 2))
    filtered = np.empty((r, 2))
    predicted = np.empty((r, 2))
    box = np.empty((r, 2))
    velocity = np.empty((r, 2))
    for a in range(rows.size):
        i = rows[a]
        tid[a], state[a], det[a], uid[a] = ints[i, TID], ints[i, STATE], det_index[i], ints[i, UID]
        measured[a] = z[i]
        filtered[a] = pos[i]
        predicted[a] = centre[i]
        box[a, 0], box[a, 1] = floats[i, W], floats[i, H]
        velocity[a] = vel[i]
    for e in range(nb.size):
        a, c = rows.size + e, keep.size + nb[e]
        j = new[nb[e]]
        tid[a], state[a], det[a], uid[a] = ints2[c, TID], ints2[c, STATE], j, ints2[c, UID]
        measured[a] = dxy[j]
        filtered[a] = dxy[j]
        predicted[a, 0] = predicted[a, 1] = np.nan
        box[a] = dwh[j]
        velocity[a, 0] = velocity[a, 1] = 0.0
    return (ints2, floats2, keep, new, tid, state, det, measured, filtered, predicted, box,
            velocity, uid, next_id, next_uid, speed2, n_speed)
