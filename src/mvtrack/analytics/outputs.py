"""Write the analytics tables as CSV files, atomically.

Files (beside ``results.txt``): ``counts.csv`` (per interval, line or zone, direction and
class), ``movements.csv`` (origin–destination counts per interval), ``speeds.csv`` (speed
statistics per interval and class) and ``tracks.csv`` (one row per track: origin,
destination, status, speeds). Numbers are written with up to 3 decimals, a missing value
(no speed, no sample) as an empty cell. Each file goes through
:func:`mvtrack.io.atomic.atomic_path`: a failure or Ctrl-C leaves the old file or none.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mvtrack.analytics.run import AnalyticsResult, Table
from mvtrack.io.atomic import atomic_path

FILES = ("counts", "movements", "speeds", "tracks")


def _cell(value: Any) -> str:
    if isinstance(value, (float, np.floating)):
        if not np.isfinite(value):
            return ""
        return f"{float(value):.3f}".rstrip("0").rstrip(".") if value != int(value) else str(
            int(value))
    if isinstance(value, (np.integer,)):
        return str(int(value))
    return str(value)


def table_csv(table: Table) -> str:
    """CSV text of a table (header, then one line per row)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    names = list(table)
    w.writerow(names)
    n = len(table[names[0]]) if names else 0
    cols = [table[k] for k in names]
    for i in range(n):  # output formatting: one line per table row
        w.writerow([_cell(c[i]) for c in cols])
    return out.getvalue()


def write_table(dest: str | os.PathLike[str], table: Table) -> Path:
    """Atomically write one table."""
    text = table_csv(table)
    with atomic_path(dest) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(dest)


def write_outputs(result: AnalyticsResult, folder: str | os.PathLike[str]) -> dict[str, Path]:
    """Write ``counts.csv``, ``movements.csv``, ``speeds.csv`` and ``tracks.csv`` into
    ``folder``; returns their paths."""
    folder = Path(folder)
    return {name: write_table(folder / f"{name}.csv", getattr(result, name)) for name in FILES}


#: a row is ``stopped`` when its track moves less than this share of its box's shorter side
#: in a second (the ``motion`` column of ``states.csv``)
STOPPED_SIDES_PER_S = 1.0


def states_table(
    log: Any, flags: Sequence[Any] | None = None, scores: Sequence[Any] | None = None,
    fps: float = 30.0,
) -> Table:
    """One row per public track row of a :class:`~mvtrack.tracking.TrackLog` (``states.csv``).

    Columns:

    - ``frame`` (1-based, as in ``results.txt``) and ``id``;
    - ``state``, the tracker's: ``confirmed`` (updated by a detection), ``stopped`` (held by
      template matching), ``coasting`` (no measurement, the prediction);
    - ``evidence`` of the row: ``detection``, ``template`` or ``prediction``;
    - ``template_score``: for a ``stopped`` row the NCC score of the template match that held
      it (at least the acceptance threshold, ``[templates] min_score``, 0.8 by default, and at
      most 1); empty for the other rows (``scores[k]`` of frame ``k``, the pair
      ``(track_id, score)`` of its held rows, as :attr:`mvtrack.video.PipelineResult.scores`
      keeps them; empty everywhere without ``scores``);
    - ``speed_px_per_frame``, the filter's speed;
    - ``motion``: ``stopped`` when the filter's speed is below the box's shorter side
      per second (``speed · fps < min(w, h)``, :data:`STOPPED_SIDES_PER_S`), else
      ``moving`` — the moving → stopped → moving of a vehicle in a queue, whichever evidence
      held the row (a waiting vehicle is held by its template once it stands, whether its
      blob faded, stays whole or broke into pieces, ``stopped`` in both; while it brakes it
      is a ``confirmed`` blob, ``stopped`` as soon as its speed is below a side a second);
    - ``blob``: for a row updated by a detection, whether its box came from a ``plain`` blob,
      from fragments ``merged`` into one predicted box or from a blob ``split`` among several
      tracks (``flags[k][j]`` of detection ``j`` of frame ``k``, as
      :attr:`mvtrack.video.PipelineResult.flags` keeps them; all ``plain`` without ``flags``);
      empty for the rows without a detection.

    Parameters
    ----------
    log : TrackLog
        The rows of the run (or of the frames not yet written, for a streaming run).
    flags : sequence, optional
        Indexed by frame number: the blob flag of each detection of the frame.
    scores : sequence, optional
        Indexed by frame number: ``(track_id, score)`` arrays of the rows the frame held by
        template matching.
    fps : float, default 30
        Frame rate of the video (for ``motion``).

    Returns
    -------
    dict of str to ndarray
        The columns, rows sorted by frame, then ID.
    """
    from mvtrack.detection.splitmerge import FLAG_NAMES
    from mvtrack.types import TrackState

    c = log.columns()
    keep = c["track_id"] > 0
    st = c["state"][keep]
    names = np.array([s.name.lower() for s in sorted(TrackState)])
    det = c["det_index"][keep]
    evidence = np.where(st == int(TrackState.STOPPED), "template",
                        np.where(det >= 0, "detection", "prediction"))
    frame0 = c["frame"][keep]
    tid = c["track_id"][keep]
    blob = np.full(det.shape, "", dtype=object)
    for i in np.flatnonzero(det >= 0):
        f = int(frame0[i])
        code = 0
        if flags is not None and f < len(flags) and det[i] < len(flags[f]):
            code = int(flags[f][det[i]])
        blob[i] = FLAG_NAMES[code]
    score = np.full(det.shape, np.nan)
    held = np.flatnonzero(st == int(TrackState.STOPPED))
    if scores is not None and held.size:
        _fill_scores(score, held, frame0[held], tid[held], scores)
    frame = frame0 + 1
    order = np.lexsort((tid, frame))
    speed = np.linalg.norm(c["velocity"][keep], axis=1)
    side = c["wh"][keep].min(axis=1) if len(speed) else np.zeros(0)
    motion = np.where(speed * fps < STOPPED_SIDES_PER_S * side, "stopped", "moving")
    return {
        "frame": frame[order],
        "id": tid[order],
        "state": names[st][order],
        "evidence": evidence[order],
        "template_score": score[order],
        "speed_px_per_frame": speed[order],
        "motion": motion[order],
        "blob": blob[order],
    }


def _fill_scores(score: np.ndarray, rows: np.ndarray, frame: np.ndarray, tid: np.ndarray,
                 scores: Sequence[Any]) -> None:
    """Put into ``score[rows]`` the score ``scores[frame]`` gives to ``(frame, tid)``."""
    frames = [f for f in np.unique(frame).tolist() if f < len(scores)]
    pairs = [(f, scores[f]) for f in frames]  # one per frame with held rows
    pairs = [(f, np.asarray(ids, np.int64), np.asarray(s, np.float64)) for f, (ids, s) in pairs
             if len(ids)]
    if not pairs:
        return
    f_tab = np.concatenate([np.full(ids.size, f, np.int64) for f, ids, _ in pairs])
    id_tab = np.concatenate([ids for _, ids, _ in pairs])
    s_tab = np.concatenate([s for _, _, s in pairs])
    span = int(max(id_tab.max(), tid.max())) + 1
    key_tab = f_tab * span + id_tab
    order = np.argsort(key_tab, kind="stable")
    key = frame.astype(np.int64) * span + tid
    pos = np.minimum(np.searchsorted(key_tab[order], key), key_tab.size - 1)
    ok = key_tab[order][pos] == key
    score[rows[ok]] = s_tab[order][pos][ok]


def read_table(path: str | os.PathLike[str]) -> dict[str, list[str]]:
    """A CSV written by :func:`write_table`, as columns of strings."""
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        return {}
    head, body = rows[0], rows[1:]
    return {h: [r[i] for r in body] for i, h in enumerate(head)}
