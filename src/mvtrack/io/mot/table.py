"""MOTChallenge rows as a struct of arrays, and per-frame views of them.

:class:`MotTable` holds the rows (frames 0-based); :class:`FrameIndex` and
:class:`DetectionFrames` build a frame when it is asked for, so their memory grows with the
rows of a file, never with its largest frame number.
"""

from __future__ import annotations

import operator
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.types import Detections, FloatArray, IntArray

Kind = Literal["det", "gt", "results"]
KINDS: tuple[str, ...] = ("det", "gt", "results")


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
