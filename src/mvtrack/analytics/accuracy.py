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


# ---------------------------------------------------------------------- scenes with truth
def scene_points(scene: Any, window: int = 7) -> TrackPoints:
    """The visible ground-truth rows of a simulated :class:`~mvtrack.sim.scene.Scene` as
    tracks (object id = track id; velocities from :func:`~mvtrack.analytics.tracks.
    local_fit`): what a perfect tracker would output."""
    vis = scene.visible
    return TrackPoints.from_arrays(scene.frame[vis], scene.id[vis], scene.xy[vis],
                                   scene.wh[vis], window=window)


def movement_counts(result: Any, include_completed: bool = True) -> dict[str, int]:
    """``"origin->destination"`` → count of an :class:`~mvtrack.analytics.run.
    AnalyticsResult`, over all intervals; ``incomplete`` counts the tracks with an unknown end
    (and, with ``include_completed=False``, the completed ones too)."""
    t = result.movements
    out: dict[str, int] = {}
    for o, d, n, c in zip(t["origin"], t["destination"], t["count"], t["completed"],
                          strict=True):
        if not n:
            continue
        known = o != "unknown" and d != "unknown"
        keep = int(n) if include_completed else int(n) - int(c)
        key = f"{o}->{d}" if known else "incomplete"
        out[key] = out.get(key, 0) + (keep if known else int(n))
        if known and not include_completed and c:
            out["incomplete"] = out.get("incomplete", 0) + int(c)
    return out


def truth_movement_counts(origin: list[str], destination: list[str]) -> dict[str, int]:
    """``"origin->destination"`` → count from per-object truth."""
    out: dict[str, int] = {}
    for o, d in zip(origin, destination, strict=True):
        out[f"{o}->{d}"] = out.get(f"{o}->{d}", 0) + 1
    return out


#: X5 (mvtrack.sim.intersection.x5_intersection): approach names by direction of travel on entry
X5_ORIGIN = ("W", "N", "E", "S")
X5_CATEGORIES = ("straight", "left", "right", "waiting")


def x5_settings() -> dict[str, Any]:
    """The ``[analytics]`` table of X5: its four approaches (the road arms outside the
    60 × 60 px intersection box), a nominal 0.25 m/px (a 16 px vehicle ≈ 4 m)."""
    from mvtrack.sim.intersection import X5_CENTRE, X5_ROAD_HALF

    cx, cy = X5_CENTRE
    h, m = X5_ROAD_HALF, X5_ROAD_HALF + 2.0
    return {
        "fps": 30.0, "interval": 12.0, "min_frames": 10,
        "calibration": {"metres_per_pixel": 0.25},
        "approaches": {
            "W": {"polygon": [[0, cy - h], [cx - m, cy - h], [cx - m, cy + h], [0, cy + h]]},
            "E": {"polygon": [[cx + m, cy - h], [320, cy - h], [320, cy + h],
                              [cx + m, cy + h]]},
            "N": {"polygon": [[cx - h, 0], [cx + h, 0], [cx + h, cy - m], [cx - h, cy - m]]},
            "S": {"polygon": [[cx - h, cy + m], [cx + h, cy + m], [cx + h, 240],
                              [cx - h, 240]]},
        },
    }


def x5_truth(scene: Any) -> dict[str, int]:
    """X5's vehicles per category (the paper's 11 / 6 / 1 / 2)."""
    return {c: int(np.sum(scene.category == c)) for c in X5_CATEGORIES}


def x5_categories(result: Any, wait: float = 2.0) -> dict[str, int]:
    """X5's categories recovered from an :class:`~mvtrack.analytics.run.AnalyticsResult`:
    every counted track with a known origin and destination is ``waiting`` when it stood
    still for at least ``wait`` seconds, else its turn (``straight``, ``left``, ``right``,
    ``u-turn``); tracks with an unknown end are ``incomplete``."""
    t = result.tracks
    out = {c: 0 for c in (*X5_CATEGORIES, "u-turn", "incomplete")}
    stopped = t.get("stopped_s", np.zeros(len(t["track_id"])))
    for counted, status, turn, st in zip(t["counted"], t["status"], t["movement"], stopped,
                                         strict=True):
        if not counted:
            continue
        if status == "incomplete":
            out["incomplete"] += 1
        elif np.isfinite(st) and st >= wait:
            out["waiting"] += 1
        else:
            out[turn] += 1
    return out


# ---------------------------------------------------------------------- files with truth
def line_counts(result: Any) -> dict[str, int]:
    """``"line:direction"`` → crossings of an :class:`~mvtrack.analytics.run.
    AnalyticsResult`, over all intervals and classes (each crossing is in the row of its
    track's class, ``all`` when the tracks carry none)."""
    t = result.counts
    out: dict[str, int] = {}
    for el, name, d, n in zip(t["element"], t["name"], t["direction"], t["count"],
                              strict=True):
        if el == "line":
            out[f"{name}:{d}"] = out.get(f"{name}:{d}", 0) + int(n)
    return out


def evaluate_analytics(gt_path: Any, pred_path: Any, settings: Any, fps: float,
                       n_frames: int | None = None) -> dict[str, Any]:
    """Count error per movement and per line direction, and speed RMSE, of a results file
    against a ground-truth file, both read as tracks and analysed with the same settings.

    The ground truth's counts are those of its own tracks (every object a perfect track), its
    speeds those of its boxes (the same fit over the same window); ground-truth rows with
    flag 0 are left out. Track rows are paired with truth rows by :func:`pair_with_truth`.
    ``speed`` is None without a calibration.
    """
    from mvtrack.analytics.run import analyse
    from mvtrack.io.mot import MotTable, read_tracks

    window = max(1, round(settings.speed.smooth * fps / 2))
    t = read_tracks(gt_path, "gt")
    keep = t.conf != 0
    t = MotTable(t.frame[keep], t.id[keep], t.tlwh[keep], np.ones(int(keep.sum())),
                 t.cls[keep], t.visibility[keep])
    gt = TrackPoints.from_mot(t, window=window, drop_tail=False)
    pred = TrackPoints.from_mot(read_tracks(pred_path, "results"), window=window)
    last = max([int(p.frame.max()) + 1 for p in (gt, pred) if len(p)], default=1)
    n = max(n_frames or 0, last)
    res_gt = analyse(gt, settings, fps, n)
    res_pred = analyse(pred, settings, fps, n)
    out: dict[str, Any] = {
        "fps": fps,
        "movements": count_errors(movement_counts(res_pred), movement_counts(res_gt)),
        "lines": count_errors(line_counts(res_pred), line_counts(res_gt)),
        "speed": None,
    }
    if settings.calibration is not None and res_gt.row_speeds is not None \
            and res_pred.row_speeds is not None:
        pair = pair_with_truth(pred, gt.frame, gt.track_id, gt.xy, gt.wh)
        out["speed"] = speed_accuracy(pred, res_pred.row_speeds, pair, res_gt.row_speeds.speed)
    return out

