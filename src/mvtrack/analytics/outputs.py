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


def states_table(log: Any) -> Table:
    """One row per public track row of a :class:`~mvtrack.tracking.TrackLog` (``states.csv``):
    ``frame`` (1-based, as in ``results.txt``), ``id``, the tracker's ``state``
    (``confirmed``: updated by a detection; ``stopped``: held by template matching;
    ``coasting``: no measurement, the prediction), the ``evidence`` of the row
    (``detection``, ``template`` or ``prediction``) and the filter's speed in px/frame."""
    from mvtrack.types import TrackState

    c = log.columns()
    keep = c["track_id"] > 0
    st = c["state"][keep]
    names = np.array([s.name.lower() for s in sorted(TrackState)])
    evidence = np.where(st == int(TrackState.STOPPED), "template",
                        np.where(c["det_index"][keep] >= 0, "detection", "prediction"))
    frame, tid = c["frame"][keep] + 1, c["track_id"][keep]
    order = np.lexsort((tid, frame))
    return {
        "frame": frame[order],
        "id": tid[order],
        "state": names[st][order],
        "evidence": evidence[order],
        "speed_px_per_frame": np.linalg.norm(c["velocity"][keep], axis=1)[order],
    }


def read_table(path: str | os.PathLike[str]) -> dict[str, list[str]]:
    """A CSV written by :func:`write_table`, as columns of strings."""
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        return {}
    head, body = rows[0], rows[1:]
    return {h: [r[i] for r in body] for i, h in enumerate(head)}
