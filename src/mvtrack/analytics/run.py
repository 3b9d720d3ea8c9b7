"""All analytics of one run, as tables of columns: counts, movements, speeds, tracks.

:func:`analyse` composes the pure functions of this package over a
:class:`~mvtrack.analytics.tracks.TrackPoints`; :func:`analyse_log` and
:func:`analyse_folder` are the edges (a :class:`~mvtrack.tracking.TrackLog`, or an output
folder with ``results.txt``). Every table is a dict of equal-length NumPy columns, in the
order they are written (:mod:`mvtrack.analytics.outputs`).

Time: frame ``k`` is at ``k / fps`` seconds; interval ``i`` is ``[i T, (i + 1) T)`` for the
interval length ``T``. A crossing belongs to the interval of its (interpolated) crossing
time, a zone visit and a movement to that of their start (for a movement: the time the track
left its origin), a speed sample to that of its row.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.lines import BACKWARD, FORWARD, line_crossings
from mvtrack.analytics.movements import (
    UNKNOWN,
    TrackMovements,
    join_fragments,
    track_movements,
)
from mvtrack.analytics.settings import AnalyticsSettings
from mvtrack.analytics.speed import (
    RowSpeeds,
    TrackSpeeds,
    group_stats,
    row_speeds,
    track_speeds,
)
from mvtrack.analytics.tracks import TrackPoints
from mvtrack.analytics.zones import occupancy, zone_visits
from mvtrack.errors import InputError

Table = dict[str, NDArray[Any]]


@dataclass
class AnalyticsResult:
    """The tables of one run and what they were computed from."""

    counts: Table
    movements: Table
    speeds: Table
    tracks: Table
    fps: float
    n_frames: int
    interval: float
    settings: AnalyticsSettings
    track_movements: TrackMovements | None = None
    row_speeds: RowSpeeds | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def n_intervals(self) -> int:
        return n_intervals(self.n_frames, self.fps, self.interval)

    def od_matrix(self, interval: int | None = None) -> tuple[list[str], NDArray[np.int64]]:
        """Approach names and the (origin × destination) counts, summed over all intervals
        or of one; incomplete movements are left out."""
        names = [a.name for a in self.settings.approaches]
        m = np.zeros((len(names), len(names)), np.int64)
        t = self.movements
        for o, d, n, i in zip(t["origin"], t["destination"], t["count"],
                              t["interval"], strict=True):
            if o in names and d in names and (interval is None or i == interval):
                m[names.index(o), names.index(d)] += n
        return names, m


def n_intervals(n_frames: int, fps: float, interval: float) -> int:
    """Number of intervals that cover frames ``0 .. n_frames - 1`` (at least 1)."""
    return max(1, int(np.ceil(n_frames / fps / interval - 1e-9)))


def _interval_of(frame: NDArray[Any], fps: float, interval: float, n: int) -> NDArray[np.int64]:
    return np.clip(np.floor(np.asarray(frame, float) / fps / interval + 1e-9), 0, n - 1).astype(
        np.int64)


def _bounds(i: NDArray[np.int64], interval: float) -> tuple[NDArray[Any], NDArray[Any]]:
    return i * interval, (i + 1) * interval


def analyse(
    tracks: TrackPoints, settings: AnalyticsSettings, fps: float, n_frames: int | None = None,
) -> AnalyticsResult:
    """Counts, movements, speeds and per-track rows of ``tracks`` (module docstring).

    Parameters
    ----------
    tracks : TrackPoints
        All rows.
    settings : AnalyticsSettings
        Lines, zones, approaches, calibration, interval.
    fps : float
        Frame rate.
    n_frames : int, optional
        Frames of the run (default: the last frame with a row, plus one).
    """
    if not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps}")
    if n_frames is None:
        n_frames = int(tracks.frame.max()) + 1 if len(tracks) else 1
    # one object's fragments are one track for everything counted below
    tracks, joined = join_fragments(tracks, fps, settings.movements)
    T = float(settings.interval)
    n_int = n_intervals(n_frames, fps, T)
    t_n = tracks.n_tracks
    lengths = np.diff(tracks.starts)
    counted_t = lengths >= settings.min_frames
    counted = counted_t[tracks.track_index] if len(tracks) else np.zeros(0, bool)
    pts = tracks.take(counted)
    track_cls = tracks.track_class()
    cls_of = dict(zip(tracks.ids.tolist(), track_cls.tolist(), strict=True))
    classes = sorted({c for c in track_cls[counted_t].tolist() if c >= 0})
    class_names = [str(c) for c in classes] or ["all"]

    speeds = None
    tspeed: TrackSpeeds | None = None
    if settings.calibration is not None and len(tracks):
        speeds = row_speeds(tracks, settings.calibration, fps, settings.speed)
        tspeed = track_speeds(tracks, speeds, fps)

    def cls_label(tid: NDArray[np.int64]) -> NDArray[np.str_]:
        c = np.array([cls_of.get(int(t), -1) for t in tid], dtype=np.int64)
        return np.where(c >= 0, c.astype(str), "all") if classes else np.full(c.size, "all")

    # ------------------------------------------------------------------ counts
    rows: dict[str, list[Any]] = {k: [] for k in (
        "interval", "interval_start_s", "interval_end_s", "element", "name", "direction",
        "class", "count", "mean_speed_kmh", "p85_speed_kmh", "mean_occupancy",
        "max_occupancy", "mean_dwell_s")}
    ivals = np.arange(n_int)

    def emit(element: str, name: str, direction: str, cls: str, count: NDArray[Any],
             mean_s: NDArray[Any], p85: NDArray[Any], occ_mean: NDArray[Any],
             occ_max: NDArray[Any], dwell: NDArray[Any]) -> None:
        lo, hi = _bounds(ivals, T)
        rows["interval"].extend(ivals.tolist())
        rows["interval_start_s"].extend(lo.tolist())
        rows["interval_end_s"].extend(hi.tolist())
        for key, val in (("element", element), ("name", name), ("direction", direction),
                         ("class", cls)):
            rows[key].extend([val] * n_int)
        for key, val in (("count", count), ("mean_speed_kmh", mean_s), ("p85_speed_kmh", p85),
                         ("mean_occupancy", occ_mean), ("max_occupancy", occ_max),
                         ("mean_dwell_s", dwell)):
            rows[key].extend(np.asarray(val).tolist())

    nan = np.full(n_int, np.nan)
    line_hits: dict[int, list[str]] = {}
    anchor = settings.anchor
    for line in settings.lines:  # a handful of lines, each vectorised over all rows
        cr = line_crossings(pts, line, anchor)
        iv = _interval_of(cr.frame, fps, T, n_int)
        lab = cls_label(cr.track_id)
        spot = (speeds.speed[np.flatnonzero(counted)[cr.row]] if speeds is not None
                else np.full(len(cr), np.nan))
        for t, d in zip(cr.track_id.tolist(), cr.direction.tolist(), strict=True):
            line_hits.setdefault(t, []).append(f"{line.name}:{line.label(d)}")
        for direction in (FORWARD, BACKWARD):
            for cname in class_names:
                sel = (cr.direction == direction) & (lab == cname)
                cnt = np.bincount(iv[sel], minlength=n_int)
                s = group_stats(spot[sel], iv[sel], n_int)
                emit("line", line.name, line.label(direction), cname, cnt, s["mean"],
                     s["p85"], nan, nan, nan)
    p_anchor = pts.anchor(anchor)
    gap = round(settings.movements.gap * fps)
    for zone in settings.zones:
        inside = zone.contains(p_anchor)
        v = zone_visits(inside, pts, gap)
        iv = _interval_of(v.first, fps, T, n_int)
        lab = cls_label(v.track_id)
        occ = occupancy(inside, pts, n_frames)
        f_iv = _interval_of(np.arange(n_frames), fps, T, n_int)
        occ_mean = np.bincount(f_iv, occ, n_int) / np.maximum(np.bincount(f_iv,
                                                                          minlength=n_int), 1)
        occ_max = np.zeros(n_int)
        np.maximum.at(occ_max, f_iv, occ)
        dw = v.dwell(fps)
        for cname in class_names:
            sel = lab == cname
            cnt = np.bincount(iv[sel], minlength=n_int)
            d = group_stats(dw[sel], iv[sel], n_int)["mean"]
            emit("zone", zone.name, "entries", cname, cnt, nan, nan, occ_mean, occ_max, d)
    counts = {k: np.asarray(v) for k, v in rows.items()}

    # ------------------------------------------------------------------ movements
    mv = None
    mrows: dict[str, list[Any]] = {k: [] for k in (
        "interval", "interval_start_s", "interval_end_s", "origin", "destination", "movement",
        "count", "completed")}
    if settings.approaches:
        mv = track_movements(pts, list(settings.approaches), fps, anchor, settings.movements)
        iv = _interval_of(mv.frame, fps, T, n_int)
        a_n = len(settings.approaches)
        o = np.where(mv.origin >= 0, mv.origin, a_n)
        d = np.where(mv.destination >= 0, mv.destination, a_n)
        ext = mv.origin_completed | mv.destination_completed
        key = (iv * (a_n + 1) + o) * (a_n + 1) + d
        size = n_int * (a_n + 1) ** 2
        cnt = np.bincount(key, minlength=size).reshape(n_int, a_n + 1, a_n + 1)
        cmp = np.bincount(key, ext, size).reshape(n_int, a_n + 1, a_n + 1)
        names = [a.name for a in settings.approaches] + [UNKNOWN]
        for i in range(n_int):
            for oi in range(a_n + 1):
                for di in range(a_n + 1):
                    known = oi < a_n and di < a_n
                    if not known and cnt[i, oi, di] == 0:
                        continue
                    mrows["interval"].append(i)
                    mrows["interval_start_s"].append(i * T)
                    mrows["interval_end_s"].append((i + 1) * T)
                    mrows["origin"].append(names[oi])
                    mrows["destination"].append(names[di])
                    mrows["movement"].append(mv.turn_of.get((oi, di), "incomplete"))
                    mrows["count"].append(int(cnt[i, oi, di]))
                    mrows["completed"].append(int(cmp[i, oi, di]))
    movements = {k: np.asarray(v) for k, v in mrows.items()}

    # ------------------------------------------------------------------ speeds per interval
    srows: dict[str, list[Any]] = {k: [] for k in (
        "interval", "interval_start_s", "interval_end_s", "class", "tracks", "samples",
        "mean_kmh", "median_kmh", "p85_kmh", "max_kmh", "stopped_share")}
    if speeds is not None and len(pts):
        sp = speeds.speed[counted]
        stp = speeds.stopped[counted]
        iv = _interval_of(pts.frame, fps, T, n_int)
        lab = cls_label(pts.track_id)
        for cname in class_names:
            sel = (lab == cname) & np.isfinite(sp)
            # one value per (interval, track): its mean moving speed in the interval
            key = iv[sel] * (t_n + 1) + pts.track_index[sel]
            uk, inv = np.unique(key, return_inverse=True)
            moving = np.where(stp[sel], np.nan, sp[sel])
            per = group_stats(moving, inv, uk.size)["mean"]
            k_iv = uk // (t_n + 1)
            s = group_stats(per, k_iv, n_int)
            n_tracks = np.bincount(k_iv, minlength=n_int)
            samples = np.bincount(iv[sel], minlength=n_int)
            stopped = np.bincount(iv[sel], stp[sel], n_int) / np.maximum(samples, 1)
            lo, hi = _bounds(ivals, T)
            for key_, val in (("interval", ivals), ("interval_start_s", lo),
                              ("interval_end_s", hi), ("class", [cname] * n_int),
                              ("tracks", n_tracks), ("samples", samples), ("mean_kmh", s["mean"]),
                              ("median_kmh", s["median"]), ("p85_kmh", s["p85"]),
                              ("max_kmh", s["max"]), ("stopped_share", stopped)):
                srows[key_].extend(np.asarray(val).tolist())
    speeds_t = {k: np.asarray(v) for k, v in srows.items()}

    # ------------------------------------------------------------------ per track
    first_f = tracks.frame[tracks.starts[:-1]] if t_n else np.zeros(0, np.int64)
    last_f = tracks.frame[tracks.starts[1:] - 1] if t_n else np.zeros(0, np.int64)
    trows: dict[str, NDArray[Any]] = {
        "track_id": tracks.ids,
        "class": np.where(track_cls >= 0, track_cls.astype(str), ""),
        "first_frame": first_f, "last_frame": last_f, "rows": lengths,
        "counted": counted_t.astype(np.int64),
    }
    origin = np.full(t_n, "", dtype=object)
    dest = np.full(t_n, "", dtype=object)
    turn = np.full(t_n, "", dtype=object)
    status = np.where(counted_t, "", "too short").astype(object)
    if mv is not None:
        pos = np.searchsorted(tracks.ids, mv.track_id)
        origin[pos] = mv.label(mv.origin)
        dest[pos] = mv.label(mv.destination)
        turn[pos] = mv.turn
        status[pos] = mv.status
    trows.update({"origin": origin.astype(str), "destination": dest.astype(str),
                  "movement": turn.astype(str), "status": status.astype(str)})
    if tspeed is not None:
        trows.update({
            "stopped_s": tspeed.stopped_s, "mean_kmh": tspeed.mean,
            "median_kmh": tspeed.median, "p85_kmh": tspeed.p85, "min_kmh": tspeed.min,
            "max_kmh": tspeed.max, "std_kmh": tspeed.std, "sigma_kmh": tspeed.sigma,
        })
    trows["crossings"] = np.array([" ".join(line_hits.get(int(t), [])) for t in tracks.ids],
                                  dtype=str) if t_n else np.zeros(0, str)
    # the tracker's IDs joined into each track (join_fragments), so that a row here can be
    # found in the tracker's results
    pieces: dict[int, list[str]] = {}
    for later, first in sorted(joined.items()):
        pieces.setdefault(first, []).append(str(later))
    trows["joined"] = np.array([" ".join(pieces.get(int(t), [])) for t in tracks.ids],
                               dtype=str) if t_n else np.zeros(0, str)
    return AnalyticsResult(counts, movements, speeds_t, trows, float(fps), int(n_frames), T,
                           settings, mv, speeds, extra={"joined": joined})


def analyse_log(log: Any, settings: AnalyticsSettings, fps: float | None = None,
                n_frames: int | None = None) -> AnalyticsResult:
    """:func:`analyse` of a :class:`~mvtrack.tracking.TrackLog` (the filter's velocities)."""
    fps = settings.fps if fps is None else fps
    if fps is None:
        raise ValueError("analytics need the frame rate: give fps (or analytics.fps)")
    if n_frames is None and len(log):
        n_frames = int(log[len(log) - 1].frame) + 1
    return analyse(TrackPoints.from_log(log), settings, fps, n_frames)


def folder_info(folder: str | os.PathLike[str]) -> dict[str, Any]:
    """``summary.json`` of an output folder ({} when absent); InputError if unreadable."""
    path = Path(folder) / "summary.json"
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: not a readable JSON summary ({exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: not a JSON object")
    return data


def analyse_folder(folder: str | os.PathLike[str], settings: AnalyticsSettings,
                   fps: float | None = None) -> AnalyticsResult:
    """:func:`analyse` of an output folder's ``results.txt`` (velocities estimated from the
    boxes, :meth:`TrackPoints.from_mot`); the frame rate from ``fps``, else the settings, else
    ``summary.json``."""
    from mvtrack.io.mot import read_tracks

    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: no such folder")
    results = folder / "results.txt"
    if not results.exists():
        raise InputError(f"{folder}: no results.txt (run mvtrack track first)")
    info = folder_info(folder)
    fps = fps if fps is not None else settings.fps
    if fps is None:
        fps = info.get("video_fps") or info.get("fps_video")
    if fps is None:
        raise InputError(f"{folder}: frame rate unknown: set analytics.fps in the settings "
                         "or pass --fps")
    table = read_tracks(results, "results")
    pts = TrackPoints.from_mot(table, window=max(1, round(settings.speed.smooth * fps / 2)))
    frames = info.get("frames")
    n_frames = int(frames) if isinstance(frames, int) and frames > 0 else None
    if n_frames is not None and len(pts):
        n_frames = max(n_frames, int(pts.frame.max()) + 1)
    res = analyse(pts, settings, float(fps), n_frames)
    res.extra["summary"] = info
    return res
