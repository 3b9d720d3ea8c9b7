r"""Offline relinking: a track that ended and one that started later are one object when the
second starts, alone, where the first one was heading.

A person hidden for a second, or missed by the detector for longer than the tracker lets a
lost track live (:mod:`mvtrack.tracking.lifecycle`), comes back as a new track. Offline both
pieces are known. An ending ``a`` (last measurement at frame ``k_a``: position ``x_a``,
velocity ``v_a`` px/frame, box ``wh_a``) and a later start ``b`` (first measurement ``x_b``,
box ``wh_b`` at frame ``k_b > `` every row of ``a``) are gated like a detection and a track
(:mod:`mvtrack.association.gate`), the position in box sizes with the variance of a
constant-velocity extrapolation over the ``T = (k_b − k_a) / f`` seconds missed:

.. math::

    d^2 = \frac{\|(x_b - x_a - v_a (k_b - k_a)) \oslash wh_a\|^2}{S(T)}
          + \frac{\|\log(wh_b \oslash wh_a)\|^2}{\sigma_s^2},\qquad
    S(T) = 2 \sigma_z^2 + (\sigma_u T)^2 \le \sigma_{max}^2

(σ_z ``measurement_noise`` at either end, σ_u :data:`SPEED_STD` the error of the track's
velocity in box sizes per second, σ_s ``size_noise``, σ_max :data:`MAX_STD`), passed when
``d² ≤`` 9.21 (99 % of a χ² with 2 degrees of freedom, the default gate). In seconds, not
frames: the same motion is relinked alike at 5 and at 30 fps. A pair is joined only when it
is unambiguous — the ending has one start in its gate and the start one ending — and the
pairs joined (each ending and each start in one at most, by construction) take the earlier
track's ID (a chain ``a → b → c`` one ID). Where two people walk side by side a motion gate
cannot tell them apart, and a wrong join costs more than the switch it saves.

This is the relinking of a detection file, by motion and size alone; the video loop relinks
online, with the boxes' appearance as well (:mod:`mvtrack.video.relink`).

Relinked gaps longer than the tracker's ``max_misses`` are not interpolated
(:func:`mvtrack.tracking.offline.track_detections`): the rows of a stretch the tracker itself
would not coast through would be guessed.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.association.distances import resolve_gate
from mvtrack.fragments import chain_heads, starts_between
from mvtrack.tracking.config import TrackerConfig
from mvtrack.tracking.log import ROW_FIELDS, concat_rows
from mvtrack.types import TrackFrame, TrackState

FloatArray = NDArray[np.float64]

#: σ_u, box sizes per second: the error of a track's velocity when it is lost; chosen by
#: leave-one-out over the frame-rate sweep (``docs/bench/framerate.md``)
SPEED_STD = 0.4

#: σ_max, box sizes: the largest std of the extrapolated position over a gap that is bridged
#: (with the defaults about 1.7 s); chosen with :data:`SPEED_STD`
MAX_STD = 0.7


def gap_variance(config: TrackerConfig, seconds: FloatArray) -> FloatArray:
    """``S(T)`` of the module, box sizes², of gaps of ``seconds``."""
    return 2.0 * config.measurement_noise**2 + (SPEED_STD * np.asarray(seconds)) ** 2


def relink(frames: list[TrackFrame], config: TrackerConfig) -> list[TrackFrame]:
    """Give a track that starts after another one ended the earlier one's ID when it is the
    same object (see the module).

    Parameters
    ----------
    frames : list of TrackFrame
        An offline run's output in increasing frame order (tracks with public IDs).
    config : TrackerConfig
        The run's settings (``measurement_noise``, ``size_noise``, ``fps``).

    Returns
    -------
    list of TrackFrame
        The same rows, the later pieces of relinked tracks renamed.
    """
    if not frames:
        return []
    c = concat_rows(frames)
    tid, fr = c["track_id"], c["frame"]
    measured = ((c["det_index"] >= 0) | (c["state"] == int(TrackState.STOPPED))) & (tid > 0)
    rows = np.flatnonzero(measured)
    if rows.size == 0:
        return list(frames)
    order = rows[np.lexsort((fr[rows], tid[rows]))]  # by track, then frame
    ids, start = np.unique(tid[order], return_index=True)
    end = np.concatenate([start[1:], [order.size]]) - 1
    head, tail = order[start], order[end]  # each track's first and last measured row
    public = tid > 0
    pos = np.searchsorted(ids, np.where(public, tid, ids[0]))
    last_row = np.zeros(ids.size, np.int64)  # each track's last row of any kind
    np.maximum.at(last_row, pos[public], fr[public])
    # the pairs: b starts after every row of a, within the longest gap bridged (found by
    # sorting the starts, so the cost follows the pairs, not the square of the tracks)
    longest = MAX_STD**2 - 2.0 * config.measurement_noise**2
    if longest <= 0.0:
        return list(frames)
    n_max = int(np.floor(np.sqrt(longest) / SPEED_STD * config.fps))  # S(n / f) <= σ_max²
    ia, ib = starts_between(fr[head], last_row + 1, fr[tail] + n_max)
    if ia.size == 0:
        return list(frames)
    gap = fr[head[ib]] - fr[tail[ia]]
    s = gap_variance(config, gap / config.fps)
    wh = c["wh"][tail[ia]]
    pred = c["filtered_xy"][tail[ia]] + c["velocity"][tail[ia]] * gap[:, None]  # x_a + v_a n
    res = (c["filtered_xy"][head[ib]] - pred) / wh  # box sizes
    value = (res**2).sum(axis=1) / s
    if config.size_noise is not None:
        value = value + (np.log(c["wh"][head[ib]] / wh) ** 2).sum(axis=1) / config.size_noise**2
    inside = value <= resolve_gate("mahalanobis")  # a χ² of 2 degrees of freedom, 99 %
    ia, ib, value = ia[inside], ib[inside], value[inside]
    # unambiguous pairs only: one start in the ending's gate, one ending in the start's
    alone = (np.bincount(ia, minlength=ids.size)[ia] == 1) & (
        np.bincount(ib, minlength=ids.size)[ib] == 1)
    src, dst = ia[alone], ib[alone]
    if src.size == 0:
        return list(frames)
    parent = np.arange(ids.size)
    parent[dst] = src
    root = chain_heads(parent)  # chains a → b → c to their first piece
    out_tid = np.where(public, ids[root][pos], tid)
    cuts = np.flatnonzero(np.diff(fr)) + 1
    return [TrackFrame(int(fr[idx[0]]), out_tid[idx], *(c[name][idx] for name in ROW_FIELDS[1:]))
            for idx in np.split(np.arange(fr.size), cuts)]
