"""Writing MOTChallenge files, atomically, in the column layout of each kind."""

from __future__ import annotations

import io
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from mvtrack.io.atomic import atomic_path
from mvtrack.io.mot.table import KINDS, Kind, MotTable
from mvtrack.types import Detections


def _as_table(rows: MotTable | ArrayLike) -> MotTable:
    return rows if isinstance(rows, MotTable) else MotTable.from_rows(rows)


def format_rows(rows: MotTable | ArrayLike, kind: Kind = "results", decimals: int = 3) -> str:
    """MOTChallenge text for ``rows`` (a :class:`MotTable`, or file-layout rows, frames 1-based).

    Rows are sorted by frame, then ID (detections keep their order within a frame).
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    table = _as_table(rows)
    if len(table) == 0:
        return ""
    if np.any(table.frame < 0):
        raise ValueError("MotTable.frame must be >= 0 (0-based frame indices)")
    if not np.isfinite(table.tlwh).all():
        raise ValueError("cannot write boxes containing NaN or inf")
    keys = (table.frame,) if kind == "det" else (table.id, table.frame)
    order = np.lexsort(keys)
    t = table.take(order)
    box = f"%.{decimals}f,%.{decimals}f,%.{decimals}f,%.{decimals}f"
    if kind == "det":
        cols = [t.frame + 1, t.tlwh, t.conf]
        fmt = f"%d,-1,{box},%.6g,-1,-1,-1"
    elif kind == "gt":
        cols = [t.frame + 1, t.id, t.tlwh, t.conf, t.cls, t.visibility]
        fmt = f"%d,%d,{box},%.6g,%d,%.6g"
    else:
        cols = [t.frame + 1, t.id, t.tlwh, t.conf]
        fmt = f"%d,%d,{box},%.6g,-1,-1,-1"
    out = io.StringIO()
    np.savetxt(out, np.column_stack(cols), fmt=fmt)
    return out.getvalue()


def write_mot(
    path: str | os.PathLike[str], rows: MotTable | ArrayLike, kind: Kind = "results",
    decimals: int = 3,
) -> Path:
    """Atomically write MOTChallenge rows (see :func:`format_rows`); returns the path."""
    text = format_rows(rows, kind, decimals)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_results(
    path: str | os.PathLike[str], rows: MotTable | ArrayLike, decimals: int = 3
) -> Path:
    """Atomically write a tracker results file (frame, id, left, top, w, h, conf, -1, -1, -1).

    Parameters
    ----------
    path : path
        Destination; never left half-written.
    rows : MotTable or (K, 6..10) array
        A table (frames 0-based) or rows in file layout (frames 1-based).
    decimals : int
        Decimals of the box coordinates.
    """
    return write_mot(path, rows, "results", decimals)


def write_detections(
    path: str | os.PathLike[str], frames: Sequence[Detections], decimals: int = 3
) -> Path:
    """Atomically write per-frame :class:`Detections` as a MOTChallenge ``det`` file."""
    return write_mot(path, MotTable.from_detections(frames), "det", decimals)
