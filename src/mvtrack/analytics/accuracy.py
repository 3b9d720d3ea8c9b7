"""Accuracy of the analytics against ground truth: count error per movement and per line,
speed RMSE.

Track rows are paired with the visible ground-truth rows of the same frame by minimum total
centre distance (Hungarian, per frame) within ``max(min_px, frac · max(w, h))`` of the true
box. A track's object is the one it is paired with in most of its paired rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.analytics.speed import RowSpeeds
from mvtrack.analytics.tracks import TrackPoints

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Pairing:
    """Per track row: the truth row it is paired with (-1: none), and per track its object
    (0: none)."""

    truth_row: IntArray
    track_object: IntArray


def pair_with_truth(
    tracks: TrackPoints, gt_frame: IntArray, gt_id: IntArray, gt_xy: FloatArray,
    gt_wh: FloatArray, min_px: float = 6.0, frac: float = 0.75,
) -> Pairing:
    """Pair track rows with truth rows frame by frame (module docstring)."""
    truth_row = np.full(len(tracks), -1, np.int64)
    order_t = np.argsort(tracks.frame, kind="stable")
    order_g = np.argsort(gt_frame, kind="stable")
    frames = np.union1d(tracks.frame, gt_frame)
    bt = np.searchsorted(tracks.frame[order_t], frames)
    et = np.searchsorted(tracks.frame[order_t], frames, side="right")
    bg = np.searchsorted(gt_frame[order_g], frames)
    eg = np.searchsorted(gt_frame[order_g], frames, side="right")
    for a, b, c, d in zip(bt, et, bg, eg, strict=True):  # evaluation: one assignment per frame
        if b == a or d == c:
            continue
        ti, gi = order_t[a:b], order_g[c:d]
        dist = np.linalg.norm(tracks.xy[ti, None] - gt_xy[None, gi], axis=-1)
        gate = np.maximum(min_px, frac * gt_wh[gi].max(axis=1))[None, :]
        cost = np.where(dist <= gate, dist, 1e9)
        r, k = linear_sum_assignment(cost)
        ok = cost[r, k] < 1e9
        truth_row[ti[r[ok]]] = gi[k[ok]]
    obj = np.zeros(tracks.n_tracks, np.int64)
    paired = truth_row >= 0
    if paired.any():
        tidx = tracks.track_index[paired]
        ids = gt_id[truth_row[paired]]
        uid, inv = np.unique(ids, return_inverse=True)
        counts = np.zeros((tracks.n_tracks, uid.size), np.int64)
        np.add.at(counts, (tidx, inv), 1)
        has = counts.sum(axis=1) > 0
        obj[has] = uid[counts[has].argmax(axis=1)]
    return Pairing(truth_row, obj)


def speed_errors(
    speeds: RowSpeeds, pairing: Pairing, truth_kmh: FloatArray,
) -> FloatArray:
    """(K,) estimated minus true speed (km/h) of every paired row (NaN unpaired)."""
    out = np.full(speeds.speed.shape, np.nan)
    ok = pairing.truth_row >= 0
    out[ok] = speeds.speed[ok] - truth_kmh[pairing.truth_row[ok]]
    return out


def speed_accuracy(
    tracks: TrackPoints, speeds: RowSpeeds, pairing: Pairing, truth_kmh: FloatArray,
    band: tuple[float, float] | None = None,
) -> dict[str, Any]:
    """RMSE, bias and coverage of the speeds against the truth.

    ``rmse_kmh`` over all paired rows with a speed (whose true speed lies in ``band`` if
    given); ``within_2sigma`` the share of those rows with ``|error| ≤ 2 σ``;
    ``stopped_rmse_kmh`` over rows whose true speed is 0; ``track_mean_rmse_kmh`` the RMSE of
    each track's mean moving speed against the mean true speed of the same rows.
    """
    err = speed_errors(speeds, pairing, truth_kmh)
    true = np.full(err.shape, np.nan)
    ok = pairing.truth_row >= 0
    true[ok] = truth_kmh[pairing.truth_row[ok]]
    use = np.isfinite(err)
    if band is not None:
        use &= (true >= band[0]) & (true <= band[1])
    e = err[use]
    sig = speeds.sigma[use]
    stopped = np.isfinite(err) & (true == 0)
    moving = use & ~speeds.stopped
    tidx = tracks.track_index[moving]
    n = np.bincount(tidx, minlength=tracks.n_tracks)
    est = np.bincount(tidx, speeds.speed[moving], tracks.n_tracks)
    tru = np.bincount(tidx, true[moving], tracks.n_tracks)
    has = n > 0
    track_err = (est[has] - tru[has]) / n[has]
    return {
        "rows": int(e.size),
        "rmse_kmh": float(np.sqrt(np.mean(e**2))) if e.size else float("nan"),
        "bias_kmh": float(np.mean(e)) if e.size else float("nan"),
        "p95_abs_error_kmh": float(np.quantile(np.abs(e), 0.95)) if e.size else float("nan"),
        "mean_sigma_kmh": float(np.nanmean(sig)) if np.isfinite(sig).any() else float("nan"),
        "within_2sigma": float(np.mean(np.abs(e) <= 2 * sig)) if e.size else float("nan"),
        "stopped_rows": int(stopped.sum()),
        "stopped_rmse_kmh": float(np.sqrt(np.mean(err[stopped] ** 2))) if stopped.any()
        else float("nan"),
        "stopped_read_zero": float(np.mean(speeds.stopped[stopped])) if stopped.any()
        else float("nan"),
        "tracks": int(has.sum()),
        "track_mean_rmse_kmh": float(np.sqrt(np.mean(track_err**2))) if has.any()
        else float("nan"),
    }


def count_errors(estimated: dict[str, int], truth: dict[str, int]) -> dict[str, dict[str, int]]:
    """Per key (a movement, or a line and direction): estimated, true and their difference;
    plus ``total`` and ``abs_error`` (the sum of |difference|)."""
    keys = sorted(set(estimated) | set(truth))
    out = {k: {"estimated": int(estimated.get(k, 0)), "truth": int(truth.get(k, 0)),
               "error": int(estimated.get(k, 0)) - int(truth.get(k, 0))} for k in keys}
    out["total"] = {"estimated": int(sum(estimated.values())),
                    "truth": int(sum(truth.values())),
                    "abs_error": int(sum(abs(v["error"]) for v in out.values()))}
    return out
