"""The last detected boxes of tracks, one row of arrays per track, kept sorted by identity.

:class:`TrackBoxes` is the bookkeeping of :class:`~mvtrack.detection.template.TemplateBank`:
for each track (an integer ``uid``, the caller's identity of it) its last full-size detected
box, its last observed and last detected centres, a reference area, its first centre and its
number of detections, as the columns of one float array; and the frame of the last
:meth:`~TrackBoxes.observe` (with its foreground mask), from which a track's template is cut
when it is first missed. A frame's update is a search, a gather, a few column operations and a
scatter, whatever the number of tracks.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
Image = NDArray[np.uint8]


def _member(a: IntArray, b: IntArray) -> BoolArray:
    """``np.isin(a, b)`` for small integer arrays, without its generic overhead."""
    if a.size == 0 or b.size == 0:
        return np.zeros(a.size, bool)
    b = np.sort(b)
    pos = np.minimum(np.searchsorted(b, a), b.size - 1)
    return b[pos] == a


class TrackBoxes:
    """Per-track rows of the last detected boxes (module docstring).

    A subclass sets the attributes below (validated) and calls :meth:`clear`; the parameters
    are those of :class:`~mvtrack.detection.template.TemplateBank`.

    Attributes
    ----------
    min_travel, min_travel_px : float
        Distance from the first detection, in box lengths and px, for :attr:`eligible`.
    min_hits : int
        Detections needed for :attr:`eligible`.
    min_fill : float
        Share of the reference area below which a detection does not replace the box.
    """

    min_travel: float
    min_travel_px: float
    min_hits: int
    min_fill: float

    # One row of ``_f`` (float64) per track, rows sorted by uid (``_u``), so that a frame's
    # update is a search, a gather, a few column operations and a scatter, whatever the number
    # of tracks. Both end with a sentinel row (uid = int64 max), so a search never runs off
    # the end. Columns: the last full-size detected box (x, y, w, h); the last observed centre
    # (a detection or a template match); the last detected centre; the reference box area
    # (running maximum, decaying 1 % per detection); the first observed centre; the tick of
    # the box (−1: none); the number of detections.
    _BOX, _LAST, _LAST_DET, _AREA, _ORIGIN, _TICK, _HITS = (
        slice(0, 4), slice(4, 6), slice(6, 8), 8, slice(9, 11), 11, 12
    )
    _NCOL = 13
    _SENTINEL = np.iinfo(np.int64).max

    def clear(self) -> None:
        """Forget everything."""
        self._u = np.array([self._SENTINEL], np.int64)
        self._f = self._empty_rows(1)
        self._tick = -1
        self._frame: Image | None = None  # the frame of tick ``_tick``
        self._mask: Image | None = None  # a copy of its foreground mask, if given
        self._mask_buf: Image | None = None

    def _empty_rows(self, n: int) -> FloatArray:
        f = np.zeros((n, self._NCOL))
        f[:, self._TICK] = -1.0
        return f

    @property
    def uids(self) -> IntArray:
        """(T,) int64: the tracks that have a recorded detection (sorted)."""
        return self._u[:-1]

    def rows(self) -> tuple[IntArray, FloatArray]:
        """The sorted uids with their sentinel last, and one row per uid (the box of
        :meth:`boxes` in columns 0–3): the bank as the compiled steps of
        :mod:`mvtrack.video.stopped` read it. Not copies; do not modify."""
        return self._u, self._f

    def __len__(self) -> int:
        return int(self._u.size - 1)

    def __contains__(self, uid: object) -> bool:
        return isinstance(uid, (int, np.integer)) and bool(np.isin(uid, self.uids))

    def _rows(self, uids: IntArray) -> tuple[IntArray, BoolArray]:
        """Row of each of ``uids`` (the sentinel's if absent) and whether it is there."""
        pos = np.searchsorted(self._u, uids)
        return pos, self._u[pos] == uids

    def observe(
        self,
        frame: Image,
        uids: ArrayLike,
        xy: ArrayLike,
        wh: ArrayLike,
        mask: Image | None = None,
    ) -> None:
        """Record this frame's detected boxes of tracks ``uids`` (their new last appearance).

        Call once per frame, after the tracker's step, with the tracks that were associated
        with a detection (``uids`` may be empty). The patches are cut lazily from this frame
        when a track is first missed
        (:meth:`~mvtrack.detection.template.TemplateBank.rescue`), so the cost here is a few
        array operations, independent of the number of tracks.

        Parameters
        ----------
        frame : (H, W, 3) or (H, W) uint8
            The frame the boxes were detected in (kept by reference until the next call).
        uids : (K,) int
            Internal track identities.
        xy, wh : (K, 2)
            Centres and sizes of the detected boxes.
        mask : (H, W) uint8, optional
            The frame's foreground mask (non-zero = object; e.g. ``detector.mask``), copied.
            With it a template holds only the object's own pixels and the search is a masked
            NCC: the road around the vehicle is left out, so a patch whose object has left
            cannot match the empty scene. Without it the whole box is the template.
        """
        uids = np.asarray(uids, np.int64).reshape(-1)
        xy = np.asarray(xy, np.float64).reshape(-1, 2)
        wh = np.asarray(wh, np.float64).reshape(-1, 2)
        if not (uids.size == xy.shape[0] == wh.shape[0]):
            raise ValueError(
                f"observe: uids, xy and wh need one row per track, got {uids.size}, "
                f"{xy.shape[0]}, {wh.shape[0]}"
            )
        if uids.size > 1:
            s = np.sort(uids)
            if (s[1:] == s[:-1]).any():
                raise ValueError("observe: uids must be distinct")
        if (uids == self._SENTINEL).any():
            raise ValueError(f"observe: uid {self._SENTINEL} is reserved")
        if mask is not None and mask.shape != frame.shape[:2]:
            raise ValueError(f"observe: mask is {mask.shape}, the frame {frame.shape[:2]}")
        self._record(frame, uids, xy, wh, mask)

    def _record(
        self, frame: Image, uids: IntArray, xy: FloatArray, wh: FloatArray, mask: Image | None
    ) -> None:
        """:meth:`observe` without the checks of its arguments (distinct uids, shapes)."""
        pos, known = self._rows(uids)
        if not known.all():  # new tracks: insert empty rows (kept sorted), then as known ones
            new = ~known
            f = self._empty_rows(int(new.sum()))
            f[:, self._ORIGIN] = xy[new]
            allu = np.concatenate([self._u, uids[new]])
            order = np.argsort(allu, kind="stable")  # the sentinel stays last
            self._u = allu[order]
            self._f = np.concatenate([self._f, f])[order]
            pos, _ = self._rows(uids)
        f = self._f[pos]
        area = wh[:, 0] * wh[:, 1]
        full = area >= self.min_fill * f[:, self._AREA]
        if full.all():  # the common case: every box is its track's new appearance
            f[:, 0:8] = np.concatenate([xy, wh, xy, xy], axis=1)  # box, last (detected) centre
            f[:, self._TICK] = self._tick + 1
        else:
            # a track whose detection just shrank keeps its last full appearance: cut it now
            # from the kept frame, before that frame is replaced (a loop over these few only)
            for r in pos[~full & (f[:, self._TICK] == self._tick)].tolist():
                self._freeze(r)
            f[full, 0:2] = xy[full]
            f[full, 2:4] = wh[full]
            f[:, self._LAST] = xy
            f[:, self._LAST_DET] = xy
            f[full, self._TICK] = self._tick + 1
        np.maximum(area, 0.99 * f[:, self._AREA], out=f[:, self._AREA])
        f[:, self._HITS] += 1.0
        self._f[pos] = f
        self._tick += 1
        self._frame = frame
        if mask is None:
            self._mask = None
        else:
            if self._mask_buf is None or self._mask_buf.shape != mask.shape:
                self._mask_buf = np.empty(mask.shape, np.uint8)
            np.copyto(self._mask_buf, mask, casting="unsafe")
            self._mask = self._mask_buf

    def _eligible_rows(self, f: FloatArray) -> BoolArray:
        """Last detection ≥ max(min_travel · box length, min_travel_px) from the first one, and
        ≥ min_hits detections (compared squared: no square root)."""
        d = f[:, self._LAST_DET] - f[:, self._ORIGIN]
        need = np.maximum(self.min_travel * np.maximum(f[:, 2], f[:, 3]), self.min_travel_px)
        return ((d * d).sum(axis=1) >= need * need) & (f[:, self._HITS] >= self.min_hits)

    def _eligible_row(self, f: list[float]) -> bool:
        """:meth:`_eligible_rows` of one row (a list), in plain float arithmetic."""
        dx = f[6] - f[9]
        dy = f[7] - f[10]
        need = max(self.min_travel * max(f[2], f[3]), self.min_travel_px)
        return dx * dx + dy * dy >= need * need and f[12] >= self.min_hits

    @property
    def eligible(self) -> BoolArray:
        """Per track in :attr:`uids`: far enough from its first detection, often enough seen."""
        return self._eligible_rows(self._f[:-1])

    def boxes(self, uids: ArrayLike) -> FloatArray:
        """(K, 4) ``(x, y, w, h)``: the box each track's template is (or will be) cut from,
        its last full-size detected box; NaN for tracks the bank does not hold.

        For a stopped vehicle this is where it stands: the blob of a vehicle fading into the
        background breaks into fragments at its edges, whose centroids (the track's last
        measurements) lie anywhere inside that box.
        """
        uids = np.asarray(uids, np.int64).reshape(-1)
        pos, has = self._rows(uids)
        out = self._f[pos, self._BOX].copy()
        out[~has] = np.nan
        return out

    def retain(self, uids: ArrayLike) -> None:
        """Keep only the tracks in ``uids`` (the live ones); forget deleted tracks."""
        keep = _member(self.uids, np.asarray(uids, np.int64).reshape(-1))
        if not keep.all():
            self._keep(keep)

    def drop(self, uids: ArrayLike) -> None:
        """Forget the tracks in ``uids`` (e.g. deleted by the tracker)."""
        gone = _member(self.uids, np.asarray(uids, np.int64).reshape(-1))
        if gone.any():
            self._keep(~gone)

    def _keep(self, keep: BoolArray) -> None:
        self._forget(self.uids[~keep].tolist())
        keep = np.append(keep, True)  # the sentinel
        self._u = self._u[keep]
        self._f = self._f[keep]

    def _freeze(self, i: int) -> None:
        """Row ``i``'s detection has just shrunk below ``min_fill``: its last full appearance
        is in the kept frame, which the caller is about to replace (nothing to do here; the
        template bank cuts its template now)."""

    def _forget(self, uids: list[int]) -> None:
        """The tracks ``uids`` are being removed (nothing to do here)."""
