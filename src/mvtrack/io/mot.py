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
``<file>:<line>: <problem>`` naming the first offending line of the file. Numbers are plain
ASCII decimals (``12``, ``-0.5``, ``1e3``); anything else (``1_0``, full-width digits, an
empty field, ``nan``, ``inf``) is refused with the same kind of message, and so are values out
of range (:data:`MAX_FRAME`, :data:`MAX_ID`, :data:`MAX_COORD`).

Memory grows with the rows of a file, never with its largest frame number: the per-frame
views (:class:`FrameIndex`, :class:`DetectionFrames`) build a frame when it is asked for.
"""

from __future__ import annotations

import io
import operator
import os
import re
import warnings
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.errors import InputError, InputWarning
from mvtrack.io.atomic import atomic_path
from mvtrack.types import Detections, FloatArray, IntArray

Kind = Literal["det", "gt", "results"]
KINDS: tuple[str, ...] = ("det", "gt", "results")

#: Accepted column counts per kind (the trailing columns are optional).
_NCOLS: dict[str, tuple[int, int]] = {"det": (7, 10), "gt": (6, 10), "results": (6, 10)}

#: Largest frame number a file may hold (1-based): about 3.9 days at 30 fps. Longer
#: recordings are split into sequences; the cap keeps a typo such as ``1e9`` from sending a
#: per-frame consumer (the tracker, the metrics) through a billion empty frames.
MAX_FRAME = 10_000_000
#: Largest magnitude of an ID (and of columns 8 to 10): the integers that float64, in which
#: files are parsed, represents exactly. Beyond it distinct IDs would collapse into one.
MAX_ID = 2**53 - 1
#: Largest magnitude of a box coordinate, width or height, in pixels.
MAX_COORD = 1e6

_SEP = re.compile(r"[ \t]*,[ \t]*|[ \t]+")
#: A character that cannot appear in rows of plain ASCII decimals sends the text to the
#: token-by-token check, which names the first bad field (``np.loadtxt`` alone would accept
#: ``nan`` and ``inf``, and reports other failures without the file's line number).
_NOT_PLAIN = re.compile(r"[^0-9eE+\-.,\n]")
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


class FrameIndex(Sequence[IntArray]):
    """Row indices of each frame ``0 .. n - 1`` of a table, without a list of ``n`` arrays.

    Element ``f`` holds the rows of frame ``f`` in table order (empty when the frame has no
    rows). The index keeps one sorted copy of the row order, so its memory is ``O(K)`` for
    ``K`` rows whatever ``n`` is; looking a frame up is a binary search. Rows of frames outside
    ``0 .. n - 1`` are left out.

    Attributes
    ----------
    frames : (F,) int64
        The frames that have rows, ascending.
    """

    __slots__ = ("_n", "_order", "_starts", "frames")

    def __init__(self, frame: IntArray, num_frames: int) -> None:
        n = operator.index(num_frames)
        if n < 0:
            raise ValueError(f"num_frames must be >= 0, got {n}")
        order = np.argsort(frame, kind="stable")
        sorted_frames = frame[order]
        lo, hi = np.searchsorted(sorted_frames, [0, n])
        self._order: IntArray = order[lo:hi]
        self.frames, first = np.unique(sorted_frames[lo:hi], return_index=True)
        self._starts: IntArray = np.append(first, hi - lo)
        self._n = n

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, key: int) -> IntArray: ...
    @overload
    def __getitem__(self, key: slice) -> list[IntArray]: ...
    def __getitem__(self, key: int | slice) -> IntArray | list[IntArray]:
        if isinstance(key, slice):
            return [self[f] for f in range(*key.indices(self._n))]
        f = operator.index(key)
        if f < 0:
            f += self._n
        if not 0 <= f < self._n:
            raise IndexError(f"frame {key} outside 0 .. {self._n - 1}")
        j = int(np.searchsorted(self.frames, f))
        if j < self.frames.size and self.frames[j] == f:
            return self._order[self._starts[j] : self._starts[j + 1]]
        return self._order[:0]

    def __iter__(self) -> Iterator[IntArray]:
        empty = self._order[:0]
        upto = 0
        for f, rows in self.groups():
            for _ in range(upto, f):
                yield empty
            yield rows
            upto = f + 1
        for _ in range(upto, self._n):
            yield empty

    @property
    def rows(self) -> IntArray:
        """Every row covered (those of frames ``0 .. n - 1``), by frame."""
        return self._order

    @property
    def num_rows(self) -> int:
        """Rows covered (those of frames ``0 .. n - 1``)."""
        return int(self._order.size)

    def groups(self) -> Iterator[tuple[int, IntArray]]:
        """``(frame, rows)`` of the frames that have rows only, ascending: ``O(K)`` steps."""
        starts = self._starts.tolist()
        for j, f in enumerate(self.frames.tolist()):
            yield f, self._order[starts[j] : starts[j + 1]]

    def __repr__(self) -> str:
        return (
            f"<FrameIndex {self._n} frames, {self.frames.size} with rows, {self.num_rows} rows>"
        )


class DetectionFrames(Sequence[Detections]):
    """One :class:`Detections` per frame ``0 .. n - 1``, built when a frame is asked for.

    What :func:`read_detections` returns. It behaves like the list of per-frame detections it
    stands for (``len``, indexing, iterating more than once) but holds only the table's rows,
    so a file whose last frame is 10⁶ costs no more memory than its rows.

    Attributes
    ----------
    table : MotTable
        The rows.
    index : FrameIndex
        Rows of each frame.
    """

    __slots__ = ("index", "table")

    def __init__(self, table: MotTable, num_frames: int | None = None) -> None:
        self.table = table
        self.index = table.frame_index(num_frames)

    def __len__(self) -> int:
        return len(self.index)

    def _frame(self, f: int, rows: IntArray) -> Detections:
        return Detections.from_tlwh(f, self.table.tlwh[rows], self.table.conf[rows])

    @overload
    def __getitem__(self, key: int) -> Detections: ...
    @overload
    def __getitem__(self, key: slice) -> list[Detections]: ...
    def __getitem__(self, key: int | slice) -> Detections | list[Detections]:
        if isinstance(key, slice):
            return [self[f] for f in range(*key.indices(len(self)))]
        f = operator.index(key)
        rows = self.index[f]  # raises IndexError outside the frames
        return self._frame(f + len(self) if f < 0 else f, rows)

    def __iter__(self) -> Iterator[Detections]:
        for f, rows in enumerate(self.index):
            yield self._frame(f, rows)

    @property
    def num_detections(self) -> int:
        """Detections in all frames together."""
        return self.index.num_rows

    def __repr__(self) -> str:
        return f"<DetectionFrames {len(self)} frames, {self.num_detections} detections>"


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
        if isinstance(frames, DetectionFrames):  # rows already in a table: O(rows), not O(frames)
            t = frames.table.take(np.sort(frames.index.rows))
            minus = np.full(len(t), -1)
            return cls(t.frame, minus, t.tlwh, t.conf, minus, minus.astype(np.float64))
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


    def frame_index(self, num_frames: int | None = None) -> FrameIndex:
        """Row indices of each frame ``0 .. num_frames - 1`` (file order kept within a frame).

        Parameters
        ----------
        num_frames : int, optional
            Number of frames to cover (defaults to :attr:`num_frames`); frames past it are
            dropped.

        Returns
        -------
        FrameIndex
            A sequence of ``num_frames`` index arrays whose memory grows with the rows only;
            :meth:`FrameIndex.groups` visits only the frames that have rows.
        """
        return FrameIndex(self.frame, self.num_frames if num_frames is None else num_frames)

    def to_detections(self, num_frames: int | None = None) -> DetectionFrames:
        """One :class:`Detections` per frame ``0 .. num_frames - 1`` (empty frames included)."""
        return DetectionFrames(self, num_frames)


# --------------------------------------------------------------------------- reading


def _fail(path: Path, line: int, problem: str) -> InputError:
    return InputError(f"{path}:{line}: {problem}")


def _num(value: float) -> str:
    """A parsed value as a user would write it: ``12``, ``2.5``, ``1e+20``."""
    if value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(float(value))


def _read_text(path: Path) -> str:
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if not path.is_file():
        raise InputError(f"{path}: not a file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file ({exc.reason} at byte {exc.start})") from None


def _bad_token(token: str) -> str | None:
    """Why ``token`` is not a plain ASCII decimal, or None when it is one."""
    if _NUMBER.fullmatch(token):
        return None
    if not token:
        return "is empty"
    if _NON_FINITE.fullmatch(token):
        return f"is {token} (NaN or inf)"
    hint = "" if token.isascii() else " (numbers are written with ASCII digits)"
    return f"is not a number: {token!r}{hint}"


def _parse(path: Path, kind: str) -> tuple[FloatArray, IntArray]:
    """Numeric rows of ``path`` and the 1-based file line number of each row."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    text = _read_text(path)
    lines = text.split("\n")
    if text.endswith("\n"):
        lines.pop()
    if "\r" in text:  # CRLF line ends
        lines = [s.rstrip("\r") for s in lines]
    if " " in text or "\t" in text:  # whitespace-separated (or padded) columns
        lines = [_SEP.sub(",", s.strip(" \t")) for s in lines]
    keep = [i for i, s in enumerate(lines) if s and not s.startswith("#")]
    lineno = np.asarray(keep, dtype=np.int64) + 1
    if not keep:
        return np.zeros((0, 10)), lineno
    body = lines if len(keep) == len(lines) else [lines[i] for i in keep]
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
    joined = "\n".join(body)
    if not _NOT_PLAIN.search(joined):
        try:
            values = np.loadtxt(
                io.StringIO(joined), delimiter=",", ndmin=2, comments=None, dtype=np.float64
            )
        except ValueError:
            pass  # a malformed field of plain characters ("", "1e", "--1"): find it below
        else:
            return values, lineno
    # Field by field, only when the fast path cannot vouch for every one.
    for i, s in enumerate(body):
        for col, token in enumerate(s.split(","), start=1):
            why = _bad_token(token)
            if why is not None:
                raise _fail(path, lineno[i], f"column {col} {why}")
    return np.array([[float(t) for t in s.split(",")] for s in body]), lineno


def _check(path: Path, kind: str, values: FloatArray, lineno: IntArray) -> None:
    """Column-wise validation; raises on the first offending line of the file."""
    finite = np.isfinite(values)
    if not finite.all():  # only from overflow ("1e999"): the parser refuses "nan" and "inf"
        row = int(np.flatnonzero(~finite.all(axis=1))[0])
        col = int(np.flatnonzero(~finite[row])[0])
        raise _fail(path, lineno[row], f"column {col + 1} is {values[row, col]} (NaN or inf)")
    problems: list[tuple[int, str]] = []  # (row, message): the first hit of each check

    def check(mask: NDArray[np.bool_], col: int, problem: str) -> None:
        hit = np.flatnonzero(mask)
        if hit.size:
            row = int(hit[0])
            problems.append((row, problem.format(v=_num(float(values[row, col])))))

    frame = values[:, 0]
    check(frame != np.round(frame), 0, "frame (column 1) is {v}, not an integer")
    check(frame < 1, 0, "frame (column 1) is {v}; MOTChallenge frames start at 1")
    check(frame > MAX_FRAME, 0, f"frame (column 1) is {{v}}, above the limit of {MAX_FRAME}")
    ids = values[:, 1]  # -1 in detection files
    check(ids != np.round(ids), 1, "id (column 2) is {v}, not an integer")
    check(np.abs(ids) > MAX_ID, 1, f"id (column 2) is {{v}}, beyond ±{MAX_ID}")
    for col, name in ((2, "left"), (3, "top")):
        check(
            np.abs(values[:, col]) > MAX_COORD, col,
            f"{name} (column {col + 1}) is {{v}}, beyond ±{MAX_COORD:.0e} pixels",
        )
    for col, name in ((4, "width"), (5, "height")):
        check(values[:, col] < 0, col, f"negative {name} (column {col + 1}): {{v}}")
        check(
            values[:, col] > MAX_COORD, col,
            f"{name} (column {col + 1}) is {{v}}, above {MAX_COORD:.0e} pixels",
        )
    for col in range(7, values.shape[1]):
        check(np.abs(values[:, col]) > MAX_ID, col, f"column {col + 1} is {{v}}, beyond ±{MAX_ID}")
    if kind == "det":
        back = np.flatnonzero(np.diff(frame) < 0)
        if back.size:
            row = int(back[0]) + 1
            problems.append((
                row,
                f"frames are not sorted (frame {_num(frame[row])} after {_num(frame[row - 1])})",
            ))
    if problems:
        row, message = min(problems)
        raise _fail(path, lineno[row], message)
    if kind != "det":
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
        The rows in file order, frames 0-based. A file without rows gives an empty table and
        an :class:`~mvtrack.errors.InputWarning`.

    Raises
    ------
    InputError
        Missing or unreadable file; wrong column count; a field that is not a plain ASCII
        decimal (``1_0``, full-width digits, an empty field), NaN or inf; a frame that is not
        an integer from 1 to :data:`MAX_FRAME`; an id that is not an integer within
        ±:data:`MAX_ID`; box coordinates or sizes beyond :data:`MAX_COORD`, negative sizes;
        unsorted frames (det); a duplicate (frame, id) (gt, results). The message is
        ``<file>:<line>: <problem>``.
    """
    path = Path(path)
    values, lineno = _parse(path, kind)
    if values.shape[0]:
        _check(path, kind, values, lineno)
    else:
        warnings.warn(
            InputWarning(f"{path}: the file has no rows (it is empty or holds only comments)"),
            stacklevel=2,
        )
    return MotTable.from_rows(values)


def read_tracks(path: str | os.PathLike[str], kind: Kind = "results") -> MotTable:
    """Read a ground-truth or results file (see :func:`read_mot`)."""
    if kind == "det":
        raise ValueError("read_tracks reads gt or results files; use read_detections for det")
    return read_mot(path, kind)


def read_detections(
    path: str | os.PathLike[str], num_frames: int | None = None
) -> DetectionFrames:
    """Read a detection file as one :class:`Detections` per frame.

    Parameters
    ----------
    path : path
        A MOTChallenge ``det`` file (frame, -1, left, top, width, height, conf, ...).
    num_frames : int, optional
        Length of the sequence. Defaults to the last frame in the file.

    Returns
    -------
    DetectionFrames
        A sequence whose element ``k`` holds frame ``k`` (0-based, file frame ``k + 1``), from
        frame 0 to the last; frames without rows are empty. ``score`` is the file's
        confidence column. Frames are built when asked for: memory grows with the rows only.
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
