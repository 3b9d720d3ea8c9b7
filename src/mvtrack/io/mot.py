"""MOTChallenge text files: detections, ground truth and tracker results.

One row per box, comma separated (whitespace is accepted too), frames 1-based in the file:

=========  ====================================================================
kind       columns
=========  ====================================================================
``det``    frame, -1, left, top, width, height, conf, x, y, z
``gt``     frame, id, left, top, width, height, conf/flag, class, visibility
``results``frame, id, left, top, width, height, conf, -1, -1, -1
=========  ====================================================================

Inside mvtrack frame indices are 0-based (``Detections.frame``, ``MotTable.frame``); the
readers subtract one and the writers add it back.

Files are parsed in one vectorised pass (``np.loadtxt``); every check then runs on whole
columns, and a failure raises :class:`~mvtrack.errors.InputError` with a one-line message
``<file>:<line>: <problem>`` naming the first offending line of the file.
"""

from __future__ import annotations

import io
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.errors import InputError
from mvtrack.io.atomic import atomic_path
from mvtrack.types import Detections, FloatArray, IntArray

Kind = Literal["det", "gt", "results"]
KINDS: tuple[str, ...] = ("det", "gt", "results")

#: Accepted column counts per kind (the trailing columns are optional).
_NCOLS: dict[str, tuple[int, int]] = {"det": (7, 10), "gt": (6, 10), "results": (6, 10)}

_SEP = re.compile(r"[ \t]*,[ \t]*|[ \t]+")


@dataclass(frozen=True)
class MotTable:
    """``K`` MOTChallenge rows as a struct of arrays.

    Attributes
    ----------
    frame : (K,) int64
        Frame index, 0-based (the file's frame minus one).
    id : (K,) int64
        Object / track ID (``-1`` in detection files).
    tlwh : (K, 4) float64
        Boxes ``(left, top, width, height)`` in pixels.
    conf : (K,) float64
        Confidence (detections, results) or the "consider" flag (ground truth); 1 when absent.
    cls : (K,) int64
        Class (ground truth); -1 when absent.
    visibility : (K,) float64
        Visible fraction (ground truth); -1 when absent.
    """

    frame: IntArray
    id: IntArray
    tlwh: FloatArray
    conf: FloatArray
    cls: IntArray
    visibility: FloatArray

    def __post_init__(self) -> None:
        frame = np.asarray(self.frame, dtype=np.int64).reshape(-1)
        k = frame.shape[0]
        fields = {
            "frame": frame,
            "id": np.asarray(self.id, dtype=np.int64).reshape(-1),
            "tlwh": np.asarray(self.tlwh, dtype=np.float64).reshape(-1, 4),
            "conf": np.asarray(self.conf, dtype=np.float64).reshape(-1),
            "cls": np.asarray(self.cls, dtype=np.int64).reshape(-1),
            "visibility": np.asarray(self.visibility, dtype=np.float64).reshape(-1),
        }
        for name, value in fields.items():
            if value.shape[0] != k:
                raise ValueError(f"MotTable: {name} has {value.shape[0]} rows, frame has {k}")
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return int(self.frame.shape[0])

    @classmethod
    def empty(cls) -> MotTable:
        """A table without rows."""
        return cls.from_rows(np.zeros((0, 10)))

    @classmethod
    def from_rows(cls, rows: ArrayLike) -> MotTable:
        """From an array of MOTChallenge rows as in a file (6 to 10 columns, frames 1-based).

        Missing trailing columns get their defaults (conf 1, class -1, visibility -1).
        """
        rows = np.asarray(rows, dtype=np.float64)
        if rows.ndim != 2 or not 6 <= rows.shape[1] <= 10:
            if rows.size == 0:
                rows = np.zeros((0, 10))
            else:
                raise ValueError(f"MOTChallenge rows must have 6 to 10 columns, got {rows.shape}")
        k, n = rows.shape
        full = np.full((k, 10), -1.0)
        full[:, 6] = 1.0
        full[:, :n] = rows
        return cls(
            frame=full[:, 0].astype(np.int64) - 1,
            id=full[:, 1].astype(np.int64),
            tlwh=full[:, 2:6],
            conf=full[:, 6],
            cls=full[:, 7].astype(np.int64),
            visibility=full[:, 8],
        )

    @classmethod
    def from_detections(cls, frames: Iterable[Detections]) -> MotTable:
        """Rows of a detection file (ID -1) from per-frame :class:`Detections`."""
        parts = [
            (np.full(len(d), d.frame), d.tlwh, d.score) for d in frames if len(d) > 0
        ]
        if not parts:
            return cls.empty()
        frame, tlwh, score = (np.concatenate(p) for p in zip(*parts, strict=True))
        k = frame.shape[0]
        minus = np.full(k, -1)
        return cls(frame, minus, tlwh, score, minus, minus.astype(np.float64))

    def to_rows(self) -> FloatArray:
        """The ``(K, 10)`` MOTChallenge rows as written to a file (frames 1-based)."""
        out = np.full((len(self), 10), -1.0)
        out[:, 0] = self.frame + 1
        out[:, 1] = self.id
        out[:, 2:6] = self.tlwh
        out[:, 6] = self.conf
        out[:, 7] = self.cls
        out[:, 8] = self.visibility
        return out

    def take(self, idx: IntArray | NDArray[np.bool_]) -> MotTable:
        """A subset (or reordering) of the rows."""
        return MotTable(
            self.frame[idx], self.id[idx], self.tlwh[idx], self.conf[idx], self.cls[idx],
            self.visibility[idx],
        )

    @property
    def num_frames(self) -> int:
        """Last frame index plus one (0 for an empty table)."""
        return int(self.frame.max()) + 1 if len(self) else 0

    def frame_index(self, num_frames: int | None = None) -> list[IntArray]:
        """Row indices of each frame ``0 .. num_frames - 1`` (file order kept within a frame).

        Parameters
        ----------
        num_frames : int, optional
            Number of frames to cover (defaults to :attr:`num_frames`); frames past it are
            dropped.
        """
        n = self.num_frames if num_frames is None else int(num_frames)
        order = np.argsort(self.frame, kind="stable")
        bounds = np.searchsorted(self.frame[order], np.arange(n + 1))
        return [order[bounds[f] : bounds[f + 1]] for f in range(n)]

    def to_detections(self, num_frames: int | None = None) -> list[Detections]:
        """One :class:`Detections` per frame ``0 .. num_frames - 1`` (empty frames included)."""
        return [
            Detections.from_tlwh(f, self.tlwh[idx], self.conf[idx])
            for f, idx in enumerate(self.frame_index(num_frames))
        ]


# --------------------------------------------------------------------------- reading


def _fail(path: Path, line: int, problem: str) -> InputError:
    return InputError(f"{path}:{line}: {problem}")


def _parse(path: Path, kind: str) -> tuple[FloatArray, IntArray]:
    """Numeric rows of ``path`` and the 1-based file line number of each row."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if not path.is_file():
        raise InputError(f"{path}: not a file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file ({exc.reason})") from None
    if " " in text or "\t" in text:  # whitespace-separated (or padded) columns
        text = _SEP.sub(",", text)
    raw = [s.strip(",") for s in text.splitlines()]
    keep = [i for i, s in enumerate(raw) if s and not s.startswith("#")]
    lineno = np.asarray(keep, dtype=np.int64) + 1
    if not keep:
        return np.zeros((0, 10)), lineno
    body = raw if len(keep) == len(raw) else [raw[i] for i in keep]
    ncols = np.fromiter((s.count(",") + 1 for s in body), dtype=np.int64, count=len(body))
    lo, hi = _NCOLS[kind]
    bad = np.flatnonzero((ncols < lo) | (ncols > hi))
    if bad.size:
        i = bad[0]
        raise _fail(
            path, lineno[i], f"expected {lo} to {hi} columns for a {kind} file, found {ncols[i]}"
        )
    bad = np.flatnonzero(ncols != ncols[0])
    if bad.size:
        i = bad[0]
        raise _fail(
            path, lineno[i], f"found {ncols[i]} columns, but line {lineno[0]} has {ncols[0]}"
        )
    try:
        values = np.loadtxt(io.StringIO("\n".join(body)), delimiter=",", ndmin=2)
    except ValueError:
        # Slow path, only on failure: find the first token that is not a number.
        for i, s in enumerate(body):
            for col, token in enumerate(s.split(","), start=1):
                try:
                    float(token)
                except ValueError:
                    raise _fail(
                        path, lineno[i], f"column {col} is not a number: {token!r}"
                    ) from None
        raise  # pragma: no cover - loadtxt failed for a reason found nowhere above
    return values, lineno


def _check(path: Path, kind: str, values: FloatArray, lineno: IntArray) -> None:
    """Column-wise validation; raises on the first offending line."""

    def first(mask: NDArray[np.bool_], problem: str) -> None:
        hit = np.flatnonzero(mask)
        if hit.size:
            raise _fail(path, lineno[hit[0]], problem)

    finite = np.isfinite(values)
    if not finite.all():
        row = np.flatnonzero(~finite.all(axis=1))[0]
        col = np.flatnonzero(~finite[row])[0]
        raise _fail(path, lineno[row], f"column {col + 1} is {values[row, col]} (NaN or inf)")
    frame = values[:, 0]
    first(frame != np.round(frame), "frame (column 1) is not an integer")
    first(frame < 1, "frame (column 1) must be >= 1 (MOTChallenge frames are 1-based)")
    if kind != "det":
        ids = values[:, 1]
        first(ids != np.round(ids), "id (column 2) is not an integer")
    first(values[:, 4] < 0, "negative width (column 5)")
    first(values[:, 5] < 0, "negative height (column 6)")
    if kind == "det":
        first(np.diff(frame, prepend=frame[:1]) < 0, "frames are not sorted (frame goes back)")
    else:
        # Each (frame, id) at most once.
        order = np.lexsort((values[:, 1], frame))
        dup = (np.diff(frame[order]) == 0) & (np.diff(values[order, 1]) == 0)
        if dup.any():
            rows = order[1:][dup]
            row = rows[np.argmin(lineno[rows])]
            raise _fail(
                path, lineno[row],
                f"id {int(values[row, 1])} appears twice in frame {int(frame[row])}",
            )


def read_mot(path: str | os.PathLike[str], kind: Kind = "results") -> MotTable:
    """Read and validate a MOTChallenge text file.

    Parameters
    ----------
    path : path
        The file.
    kind : {"det", "gt", "results"}
        Its layout. Detection files must be sorted by frame; ground-truth and result files
        may come in any order but each (frame, id) pair at most once.

    Returns
    -------
    MotTable
        The rows in file order, frames 0-based.

    Raises
    ------
    InputError
        Missing file, wrong column count, non-numeric value, NaN or inf, frame < 1 or not an
        integer, negative width or height, unsorted frames (det), duplicate (frame, id)
        (gt, results). The message is ``<file>:<line>: <problem>``.
    """
    path = Path(path)
    values, lineno = _parse(path, kind)
    if values.shape[0]:
        _check(path, kind, values, lineno)
    return MotTable.from_rows(values)


def read_tracks(path: str | os.PathLike[str], kind: Kind = "results") -> MotTable:
    """Read a ground-truth or results file (see :func:`read_mot`)."""
    if kind == "det":
        raise ValueError("read_tracks reads gt or results files; use read_detections for det")
    return read_mot(path, kind)


def read_detections(
    path: str | os.PathLike[str], num_frames: int | None = None
) -> list[Detections]:
    """Read a detection file as one :class:`Detections` per frame.

    Parameters
    ----------
    path : path
        A MOTChallenge ``det`` file (frame, -1, left, top, width, height, conf, ...).
    num_frames : int, optional
        Length of the sequence. Defaults to the last frame in the file.

    Returns
    -------
    list of Detections
        Element ``k`` holds frame ``k`` (0-based, file frame ``k + 1``), from frame 0 to the
        last; frames without rows are empty. ``score`` is the file's confidence column.
    """
    table = read_mot(path, "det")
    return table.to_detections(num_frames)


# --------------------------------------------------------------------------- writing


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
