"""The compiled steps of the stopped-vehicle rescue (:mod:`mvtrack.video.stopped`) against
the array computations they replace, on random track tables, template banks and detections
(compiled and ``py_func``)."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack.tracking.lifecycle import LAST_X, LAST_Y, N_FLOAT, N_INT, TID, UID
from mvtrack.video import stopped

SENTINEL = np.iinfo(np.int64).max


def _scene(rng: np.random.Generator):  # type: ignore[no-untyped-def]
    n, m = int(rng.integers(1, 8)), int(rng.integers(0, 6))
    ints = np.zeros((n, N_INT), np.int64)
    ints[:, UID] = rng.permutation(np.arange(1, 3 * n + 1))[:n]
    ints[:, TID] = np.where(rng.random(n) < 0.8, rng.integers(1, 50, n), -1)
    floats = np.zeros((n, N_FLOAT))
    floats[:, LAST_X:LAST_Y + 1] = rng.uniform(0, 40, (n, 2)).round(int(rng.integers(0, 3)))
    held = np.sort(rng.choice(ints[:, UID], int(rng.integers(0, n + 1)), replace=False))
    bank_u = np.append(held, SENTINEL).astype(np.int64)
    bank_f = np.full((held.size + 1, 13), np.nan)
    bank_f[:-1, :2] = rng.uniform(0, 40, (held.size, 2)).round(1)
    bank_f[:-1, 2:4] = rng.uniform(2, 16, (held.size, 2)).round(1)
    bank_f[:-1][rng.random(held.size) < 0.15, 2] = np.nan  # rows without a full box
    det_xy = rng.uniform(0, 40, (m, 2)).round(1)
    det_wh = rng.uniform(1, 20, (m, 2)).round(1)
    if held.size:  # tracks measured near their template's box, pieces of them inside it
        rows = np.flatnonzero(np.isin(ints[:, UID], held) & (rng.random(n) < 0.7))
        at = np.searchsorted(bank_u, ints[rows, UID])
        floats[rows, LAST_X:LAST_Y + 1] = bank_f[at, :2] + rng.normal(0, 3, (rows.size, 2))
        pieces = bank_f[rng.integers(0, held.size, 3), :2] + rng.normal(0, 2, (3, 2))
        det_xy = np.vstack([det_xy, pieces.round(1)])
        det_wh = np.vstack([det_wh, rng.uniform(1, 6, (3, 2)).round(1)])
    return ints, floats, bank_u, bank_f, det_xy, det_wh


def _boxes(bank_u, bank_f, uids):  # type: ignore[no-untyped-def]
    pos = np.searchsorted(bank_u, uids)
    out = bank_f[pos, 0:4].copy()
    out[bank_u[pos] != uids] = np.nan
    return out


def _near(last, box):  # type: ignore[no-untyped-def]
    reach = box[:, 2:] / 2 + box[:, 2:].max(axis=1, keepdims=True)
    return (np.abs(last - box[:, :2]) <= reach).all(axis=1)


def _within(box, xy, wh, shift):  # type: ignore[no-untyped-def]
    half = box[:, None, 2:] / 2 + shift
    return ((xy - wh / 2)[None] >= box[:, None, :2] - half).all(axis=2) & (
        (xy + wh / 2)[None] <= box[:, None, :2] + half).all(axis=2)


def _kernel(name: str, compiled: bool):  # type: ignore[no-untyped-def]
    fn = getattr(stopped, name)
    return fn if compiled else fn.py_func


@pytest.mark.parametrize("compiled", [True, False])
def test_standing_pieces_and_missed_places(compiled: bool) -> None:
    pieces, places = _kernel("standing_pieces", compiled), _kernel("missed_places", compiled)
    rng = np.random.default_rng(3)
    found = 0
    for _ in range(400):
        ints, floats, bank_u, bank_f, det_xy, det_wh = _scene(rng)
        uid, last_xy = ints[:, UID], floats[:, LAST_X:LAST_Y + 1]
        standing = np.sort(rng.choice(uid, int(rng.integers(0, uid.size + 1)), replace=False))
        live = np.flatnonzero((ints[:, TID] > 0) & np.isin(uid, standing))
        box = _boxes(bank_u, bank_f, uid[live])
        inside = _within(box, det_xy, det_wh, 4.0) & _near(last_xy[live], box)[:, None]
        cand = np.flatnonzero(inside.any(axis=1))
        got = pieces(ints, floats, standing.astype(np.int64), bank_u, bank_f, det_xy, det_wh,
                     4.0)
        np.testing.assert_array_equal(got[0], uid[live][cand])
        np.testing.assert_array_equal(got[1], box[cand])
        np.testing.assert_array_equal(got[2], inside[cand])
        found += cand.size
        # the missed tracks' rows, template boxes and search centres
        uids = rng.permutation(uid)[: int(rng.integers(0, uid.size + 1))]
        order = np.argsort(uid)
        at = order[np.searchsorted(uid[order], uids)]
        box = _boxes(bank_u, bank_f, uids)
        last = last_xy[at]
        centre = np.where(_near(last, box)[:, None], box[:, :2], last)
        got = places(ints, floats, uids, bank_u, bank_f)
        for a, b in zip(got, (at, last, box, centre), strict=True):
            np.testing.assert_array_equal(a, b)
    assert found > 30


@pytest.mark.parametrize("compiled", [True, False])
def test_cached_matches(compiled: bool) -> None:
    cached = _kernel("cached_matches", compiled)
    rng = np.random.default_rng(5)
    for _ in range(300):
        c_uid = rng.permutation(20)[: int(rng.integers(1, 6))].astype(np.int64)
        c_xy = rng.uniform(0, 20, (c_uid.size, 2)).round(0)
        uids = rng.permutation(20)[: int(rng.integers(0, 6))].astype(np.int64)
        centre = rng.uniform(0, 20, (uids.size, 2)).round(0)
        order = np.argsort(c_uid)
        pos = np.minimum(np.searchsorted(c_uid[order], uids), c_uid.size - 1)
        done = (c_uid[order][pos] == uids) & (
            np.abs(c_xy[order][pos] - centre) <= 4.0).all(axis=1)
        want = np.where(done, order[pos], -1)
        np.testing.assert_array_equal(cached(c_uid, c_xy, uids, centre, 4.0), want)


def _accept_reference(found, xy, velocity, frames, wh, box, stood, det_xy, det_wh):  # type: ignore[no-untyped-def]
    found, xy = found.copy(), xy.copy()
    template = box[:, 2:]
    size = np.where(np.isfinite(template), np.maximum(template, wh), wh)
    found &= ~((np.abs(velocity) * frames.astype(np.float64)[:, None]) > size / 2).any(axis=1)
    if not found.any():
        return found, xy
    if len(det_xy):
        lo, hi = det_xy - det_wh / 2, det_xy + det_wh / 2
        inside = ((xy[:, None, :] >= lo[None]) & (xy[:, None, :] <= hi[None])).all(2)
        merged = det_wh.prod(axis=1)[None, :] > 2.5 * wh.prod(axis=1)[:, None]
        if stood.any():
            merged[stood] |= ~_within(box[stood], det_xy, det_wh, 4.0)
        found &= ~(inside & ~merged).any(axis=1)
    xy[~found] = np.nan
    return found, xy


@pytest.mark.parametrize("compiled", [True, False])
def test_accept_stopped(compiled: bool) -> None:
    accept = _kernel("accept_stopped", compiled)
    rng = np.random.default_rng(11)
    kept = 0
    for _ in range(500):
        k, m = int(rng.integers(1, 5)), int(rng.integers(0, 5))
        found = rng.random(k) < 0.8
        xy = rng.uniform(0, 30, (k, 2)).round(0)
        velocity = rng.normal(0, 0.5, (k, 2))
        velocity[rng.random(k) < 0.2] = np.nan
        frames = rng.integers(1, 6, k).astype(np.int64)
        wh = rng.uniform(2, 12, (k, 2)).round(0)
        box = np.hstack([xy + rng.normal(0, 2, (k, 2)), rng.uniform(2, 14, (k, 2))]).round(0)
        box[rng.random(k) < 0.2] = np.nan
        stood = rng.random(k) < 0.5
        det_xy = rng.uniform(0, 30, (m, 2)).round(0)
        det_wh = rng.uniform(2, 40, (m, 2)).round(0)
        want = _accept_reference(found, xy, velocity, frames, wh, box, stood, det_xy, det_wh)
        accept(found, xy, velocity, frames, wh, box, stood, det_xy, det_wh, 2.5, 4.0)
        np.testing.assert_array_equal(found, want[0])
        np.testing.assert_array_equal(xy, want[1])
        kept += found.sum()
    assert kept > 50
