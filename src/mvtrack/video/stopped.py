"""The array steps of the stopped-vehicle rescue around its NCC searches, compiled.

:class:`~mvtrack.video.rescue.StoppedVehicleRescuer` runs, every frame, a few searches of
one or two tracks each; around each it chose, looked up and checked its tracks with a dozen
or more small array operations, which cost far more than the searches. Each group of them is
one call here, with the same arithmetic:

- :func:`standing_pieces`: the standing tracks with a detection inside their template's box
  (:meth:`~mvtrack.video.rescue.StoppedVehicleRescuer.fragments`);
- :func:`missed_places`: each missed track's row, template box and search centre
  (the place where its vehicle was last seen);
- :func:`cached_matches`: the matches a frame's first search already found;
- :func:`accept_stopped`: what a stopped vehicle looks like
  (:func:`could_stand`, no detection of its size covering it).

The track table is passed whole (``ints``, ``floats``, C-contiguous; columns of
:mod:`mvtrack.tracking.lifecycle`), the template bank as its sorted uids and rows
(:class:`~mvtrack.detection.track_boxes.TrackBoxes`: box in columns 0–3, a sentinel row last).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.jit import kernel
from mvtrack.tracking.lifecycle import LAST_X, LAST_Y, TID, UID

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


@kernel
def bank_box(bank_u: IntArray, bank_f: FloatArray, uid: int, out: FloatArray) -> None:
    """``out`` (4,): the template box ``(x, y, w, h)`` of ``uid``, NaN where the bank (sorted
    ``bank_u`` with its sentinel last, rows ``bank_f``) does not hold it."""
    pos = np.searchsorted(bank_u, uid)
    for c in range(4):
        out[c] = bank_f[pos, c] if bank_u[pos] == uid else np.nan


@kernel
def _reach_ok(last_x: float, last_y: float, box: FloatArray) -> bool:
    """The last measurement within one box length of the box (each axis
    ``|last − centre| ≤ size/2 + max(w, h)``; NaN: False)."""
    w, h = box[2], box[3]
    longest = w if (w > h or w != w) else h  # NumPy's max: NaN wins
    return (abs(last_x - box[0]) <= w / 2 + longest
            and abs(last_y - box[1]) <= h / 2 + longest)


@kernel
def _covers(box: FloatArray, x: float, y: float, w: float, h: float, margin: float) -> bool:
    """The detection ``(x, y, w, h)`` lies inside ``box`` widened by ``margin`` px on every
    side (False for a NaN box)."""
    hx, hy = box[2] / 2 + margin, box[3] / 2 + margin
    return (x - w / 2 >= box[0] - hx and y - h / 2 >= box[1] - hy
            and x + w / 2 <= box[0] + hx and y + h / 2 <= box[1] + hy)


@kernel
def standing_pieces(
    ints: IntArray, floats: FloatArray, standing: IntArray, bank_u: IntArray,
    bank_f: FloatArray, det_xy: FloatArray, det_wh: FloatArray, max_shift: float,
) -> tuple[IntArray, FloatArray, BoolArray]:
    """The confirmed tracks among ``standing`` (sorted uids) last measured within one box
    length of their template's box with a detection inside that box widened by
    ``max_shift``: their uids (in table order), template boxes (K, 4) and which detections
    lie inside (K, M)."""
    n, m = ints.shape[0], det_xy.shape[0]
    uids = np.empty(n, np.int64)
    boxes = np.empty((n, 4))
    inside = np.zeros((n, m), np.bool_)
    k = 0
    for r in range(n):
        uid = ints[r, UID]
        if ints[r, TID] <= 0 or standing.size == 0:
            continue
        pos = np.searchsorted(standing, uid)
        if pos >= standing.size or standing[pos] != uid:
            continue
        bank_box(bank_u, bank_f, uid, boxes[k])
        if not _reach_ok(floats[r, LAST_X], floats[r, LAST_Y], boxes[k]):
            continue
        hit = False
        for j in range(m):
            if _covers(boxes[k], det_xy[j, 0], det_xy[j, 1], det_wh[j, 0], det_wh[j, 1],
                       max_shift):
                inside[k, j] = True
                hit = True
        if hit:
            uids[k] = uid
            k += 1
        else:
            inside[k, :] = False
    return uids[:k].copy(), boxes[:k].copy(), inside[:k].copy()


@kernel
def missed_places(
    ints: IntArray, floats: FloatArray, uids: IntArray, bank_u: IntArray, bank_f: FloatArray,
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray]:
    """For each of ``uids`` (uids of the table's tracks): its row in the table, last
    measurement (K, 2), template box (K, 4; NaN without one) and where its vehicle was last
    seen (K, 2): the box's centre when the last measurement lies within one box length of it,
    else the last measurement."""
    k, n = uids.size, ints.shape[0]
    at = np.empty(k, np.int64)
    last = np.empty((k, 2))
    box = np.empty((k, 4))
    centre = np.empty((k, 2))
    for i in range(k):
        r = 0
        while r < n - 1 and ints[r, UID] != uids[i]:
            r += 1
        at[i] = r
        last[i, 0], last[i, 1] = floats[r, LAST_X], floats[r, LAST_Y]
        bank_box(bank_u, bank_f, uids[i], box[i])
        if _reach_ok(last[i, 0], last[i, 1], box[i]):
            centre[i, 0], centre[i, 1] = box[i, 0], box[i, 1]
        else:
            centre[i, 0], centre[i, 1] = last[i, 0], last[i, 1]
    return at, last, box, centre


@kernel
def cached_matches(cache_uids: IntArray, cache_xy: FloatArray, uids: IntArray,
                   centre: FloatArray, max_shift: float) -> IntArray:
    """Index into the cache of each of ``uids`` matched there within ``max_shift`` px of its
    ``centre`` on each axis; −1 where not."""
    hit = np.full(uids.size, -1, np.int64)
    for i in range(uids.size):
        for j in range(cache_uids.size):
            if (cache_uids[j] == uids[i]
                    and abs(cache_xy[j, 0] - centre[i, 0]) <= max_shift
                    and abs(cache_xy[j, 1] - centre[i, 1]) <= max_shift):
                hit[i] = j
                break
    return hit


@kernel
def could_stand(velocity: FloatArray, frames: IntArray, size: FloatArray) -> BoolArray:
    r"""Whether each vehicle can be standing where it was last measured.

    Its filter's velocity ``v`` (px/frame) over the ``Δk`` frames since that measurement would
    carry it ``v Δk``; it still covers that place if, on each axis,

    .. math:: |v_a| \, Δk \le s_a / 2

    (its last measured centre still inside its box of size ``s``). A vehicle that slowed down
    and stopped passes (``v`` came to rest with it); one missed while it drives on does not,
    and the template match at its last place is the road it left. No new constant: the
    vehicle's own size and speed decide.

    Parameters
    ----------
    velocity : (K, 2)
        The tracks' velocities, px/frame (NaN: no evidence, it passes).
    frames : (K,) int
        Frames since each track's last measurement (at least 1 when it missed this one).
    size : (K, 2)
        The vehicles' box sizes ``(w, h)``, px.
    """
    k = velocity.shape[0]
    out = np.ones(k, np.bool_)
    for i in range(k):
        for c in range(2):
            if abs(velocity[i, c]) * np.float64(frames[i]) > size[i, c] / 2:  # NaN: False
                out[i] = False
    return out


@kernel
def accept_stopped(
    found: BoolArray, xy: FloatArray, velocity: FloatArray, frames: IntArray, wh: FloatArray,
    box: FloatArray, stood: BoolArray, det_xy: FloatArray, det_wh: FloatArray, merged: float,
    max_shift: float,
) -> None:
    """Keep (in place) the matches of tracks that could stand there and that no detection of
    about their size covers; when one is kept, ``xy`` is NaN where refused.

    A track could stand when on each axis ``|v| Δk ≤ s/2`` (NaN velocity: it could), ``s``
    the larger of its box ``wh`` and its template's ``box``
    (:func:`could_stand`). A detection covers the match when the match
    lies inside it; it does not count when it is over ``merged`` times the track's area
    (vehicles merged into one blob), nor, for a track that ``stood`` (held by its template in
    the last frame), when it reaches out of the template's box widened by ``max_shift``.
    """
    k = found.size
    size = wh.copy()
    for i in range(k):
        for c in range(2):
            t = box[i, 2 + c]
            if np.isfinite(t) and not t <= size[i, c]:  # NumPy's maximum (NaN size stays)
                size[i, c] = t if size[i, c] == size[i, c] else size[i, c]
    found &= could_stand(velocity, frames, size)
    left = found.any()
    if not left:
        return
    for i in range(k):
        if found[i]:
            area = wh[i, 0] * wh[i, 1]
            for j in range(det_xy.shape[0]):
                hx, hy = det_wh[j, 0] / 2, det_wh[j, 1] / 2
                if not (xy[i, 0] >= det_xy[j, 0] - hx and xy[i, 1] >= det_xy[j, 1] - hy
                        and xy[i, 0] <= det_xy[j, 0] + hx and xy[i, 1] <= det_xy[j, 1] + hy):
                    continue
                big = det_wh[j, 0] * det_wh[j, 1] > merged * area
                if stood[i] and not _covers(box[i], det_xy[j, 0], det_xy[j, 1], det_wh[j, 0],
                                            det_wh[j, 1], max_shift):
                    big = True
                if not big:
                    found[i] = False
                    break
        if not found[i]:
            xy[i, 0] = np.nan
            xy[i, 1] = np.nan
