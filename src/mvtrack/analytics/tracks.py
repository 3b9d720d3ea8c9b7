"""The rows of all tracks as one struct of arrays, sorted by track then frame.

Every analytic reads a :class:`TrackPoints`: from a :class:`~mvtrack.tracking.TrackLog`
(the filter's positions and velocities, :meth:`TrackPoints.from_log`) or from a MOTChallenge
results file (:meth:`TrackPoints.from_mot`, where the velocity is estimated from the boxes,
:func:`local_fit`). Windows over the rows of each track are vectorised by looping over the
*offsets* of the window (a few dozen array operations over all rows), never over tracks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.types import TrackState

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: state value of rows whose life-cycle state is unknown (rows read from a results file)
UNKNOWN_STATE = -1
ANCHORS = ("centre", "foot")


@dataclass(frozen=True, eq=False)
class TrackPoints:
    """``K`` track rows sorted by ``(track_id, frame)``, each ``(frame, track_id)`` once.

    Attributes
    ----------
    frame, track_id : (K,) int64
        Frame index (0-based) and public track ID (> 0).
    xy : (K, 2) float64
        The filtered box centre, px.
    wh : (K, 2) float64
        Box width and height, px.
    velocity : (K, 2) float64
        Velocity of the centre, px/frame: the filter's (``velocity_source == "filter"``) or
        estimated from the positions (``"estimated"``).
    measured_xy : (K, 2) float64
        The measurement of the row (NaN where the row has none: coasting, interpolated).
    state : (K,) int64
        :class:`~mvtrack.types.TrackState`, or :data:`UNKNOWN_STATE`.
    cls : (K,) int64
        Object class (-1: unknown).
    velocity_source : str
        ``"filter"`` or ``"estimated"``.
    """

    frame: IntArray
    track_id: IntArray
    xy: FloatArray
    wh: FloatArray
    velocity: FloatArray
    measured_xy: FloatArray
    state: IntArray
    cls: IntArray
    velocity_source: str = "filter"

    def __post_init__(self) -> None:
        k = self.frame.shape[0]
        for name in ("track_id", "state", "cls"):
            if getattr(self, name).shape != (k,):
                raise ValueError(f"TrackPoints: {name} must have shape ({k},)")
        for name in ("xy", "wh", "velocity", "measured_xy"):
            if getattr(self, name).shape != (k, 2):
                raise ValueError(f"TrackPoints: {name} must have shape ({k}, 2)")
        if k > 1:
            step = np.diff(self.track_id)
            bad = (step < 0) | ((step == 0) & (np.diff(self.frame) <= 0))
            if bad.any():
                raise ValueError("TrackPoints: rows must be sorted by track, then frame, "
                                 "with each (frame, track) once")
        first = np.ones(k, dtype=bool)
        first[1:] = self.track_id[1:] != self.track_id[:-1]
        starts = np.flatnonzero(first)
        object.__setattr__(self, "_first", first)
        object.__setattr__(self, "_starts", np.append(starts, k))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_arrays(
        cls,
        frame: NDArray,
        track_id: NDArray,
        xy: NDArray,
        wh: NDArray,
        velocity: NDArray | None = None,
        measured_xy: NDArray | None = None,
        state: NDArray | None = None,
        classes: NDArray | None = None,
        window: int = 7,
    ) -> TrackPoints:
        """From rows in any order; sorts them. Without ``velocity`` it is estimated by
        :func:`local_fit` over ``± window`` frames."""
        frame = np.asarray(frame, np.int64).reshape(-1)
        tid = np.asarray(track_id, np.int64).reshape(-1)
        k = frame.shape[0]
        order = np.lexsort((frame, tid))
        xy = np.asarray(xy, np.float64).reshape(k, 2)[order]
        meas = xy.copy() if measured_xy is None else np.asarray(measured_xy, float).reshape(
            k, 2)[order]
        st = np.full(k, UNKNOWN_STATE, np.int64) if state is None else np.asarray(
            state, np.int64).reshape(k)[order]
        cl = np.full(k, -1, np.int64) if classes is None else np.asarray(
            classes, np.int64).reshape(k)[order]
        frame, tid = frame[order], tid[order]
        source = "filter"
        if velocity is None:
            vel = local_fit(frame, tid, xy, window).slope
            source = "estimated"
        else:
            vel = np.asarray(velocity, np.float64).reshape(k, 2)[order]
        return cls(frame, tid, xy, np.asarray(wh, np.float64).reshape(k, 2)[order], vel,
                   meas, st, cl, source)

    @classmethod
    def from_log(cls, log: object, *, drop_tail: bool = True) -> TrackPoints:
        """The public rows of a :class:`~mvtrack.tracking.TrackLog`.

        ``drop_tail`` leaves out each track's coasting rows after its last measured row (a
        prediction past the track's end is not where the object went); coasting rows between
        measurements (bridged or interpolated gaps) are kept.
        """
        c = log.columns()  # type: ignore[attr-defined]
        keep = c["track_id"] > 0
        pts = cls.from_arrays(
            c["frame"][keep], c["track_id"][keep], c["filtered_xy"][keep], c["wh"][keep],
            velocity=c["velocity"][keep],
            measured_xy=np.where(
                ((c["det_index"] >= 0) | (c["state"] == int(TrackState.STOPPED)))[keep, None],
                c["measured_xy"][keep], np.nan),
            state=c["state"][keep],
        )
        return pts.without_tails() if drop_tail else pts

    @classmethod
    def from_mot(cls, table: object, *, window: int = 7, drop_tail: bool = True) -> TrackPoints:
        """The rows of a MOTChallenge results table (:class:`~mvtrack.io.mot.MotTable`).

        Box centres are the positions; rows with ``conf`` < 1 (coasting predictions, as
        :meth:`~mvtrack.tracking.TrackLog.to_mot` writes them) count as unmeasured. The
        velocity is estimated by :func:`local_fit` over ``± window`` frames; the class is the
        file's 8th column where it is ≥ 0.
        """
        tlwh = table.tlwh  # type: ignore[attr-defined]
        xy = tlwh[:, :2] + tlwh[:, 2:] / 2
        measured = table.conf >= 1.0  # type: ignore[attr-defined]
        pts = cls.from_arrays(
            table.frame, table.id, xy, tlwh[:, 2:],  # type: ignore[attr-defined]
            measured_xy=np.where(measured[:, None], xy, np.nan),
            classes=np.where(table.cls >= 0, table.cls, -1),  # type: ignore[attr-defined]
            window=window,
        )
        return pts.without_tails() if drop_tail else pts

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return int(self.frame.shape[0])

    @property
    def first(self) -> BoolArray:
        """(K,) the row is its track's first."""
        return self._first  # type: ignore[attr-defined, no-any-return]

    @property
    def starts(self) -> IntArray:
        """(T + 1,) row index where each track starts, then ``K``."""
        return self._starts  # type: ignore[attr-defined, no-any-return]

    @property
    def ids(self) -> IntArray:
        """(T,) the track IDs, ascending."""
        return self.track_id[self.starts[:-1]]

    @property
    def n_tracks(self) -> int:
        return int(self.starts.shape[0] - 1)

    @property
    def track_index(self) -> IntArray:
        """(K,) index ``0 .. T-1`` of each row's track."""
        return np.cumsum(self.first) - 1

    @property
    def measured(self) -> BoolArray:
        """(K,) the row carries a measurement."""
        return np.isfinite(self.measured_xy).all(axis=1)

    def anchor(self, which: str = "centre") -> FloatArray:
        """The point of each box that is counted and measured: ``"centre"`` or ``"foot"``
        (the bottom centre, where a vehicle or a person touches the ground)."""
        if which == "centre":
            return self.xy
        if which == "foot":
            return self.xy + np.column_stack([np.zeros(len(self)), self.wh[:, 1] / 2])
        raise ValueError(f"anchor must be one of {', '.join(ANCHORS)}, got {which!r}")

    def take(self, keep: BoolArray | IntArray) -> TrackPoints:
        """A subset of the rows (order kept)."""
        return TrackPoints(
            self.frame[keep], self.track_id[keep], self.xy[keep], self.wh[keep],
            self.velocity[keep], self.measured_xy[keep], self.state[keep], self.cls[keep],
            self.velocity_source,
        )

    def without_tails(self) -> TrackPoints:
        """Without each track's unmeasured rows after its last measured row."""
        meas = self.measured
        if meas.all() or len(self) == 0:
            return self
        k = len(self)
        pos = np.where(meas, np.arange(k), -1)
        # last measured row of each track, at or after every row (reverse running max)
        tidx = self.track_index
        last = np.full(self.n_tracks, -1, np.int64)
        np.maximum.at(last, tidx, pos)
        return self.take(np.arange(k) <= last[tidx])

    def track_class(self) -> IntArray:
        """(T,) each track's class: the most frequent non-negative class of its rows (-1)."""
        out = np.full(self.n_tracks, -1, np.int64)
        ok = self.cls >= 0
        if not ok.any():
            return out
        classes, inv = np.unique(self.cls[ok], return_inverse=True)
        counts = np.zeros((self.n_tracks, classes.size), np.int64)
        np.add.at(counts, (self.track_index[ok], inv), 1)
        has = counts.sum(axis=1) > 0
        out[has] = classes[counts[has].argmax(axis=1)]
        return out


# ---------------------------------------------------------------------- windows over tracks
@dataclass(frozen=True)
class LocalFit:
    """Per row, a straight line ``x(t) = x_i + a + b (t - t_i)`` fitted by least squares to the
    rows of the same track within the window.

    Attributes
    ----------
    slope : (K, 2) float64
        ``b``, px/frame (NaN where fewer than 2 rows).
    se : (K,) float64
        Standard error of each component of ``b`` (px/frame), from the pooled residual
        variance of both axes, ``s² = (RSS_x + RSS_y) / (2 (n - 2))``, and
        ``SE² = s² / Σ (t - t̄)²``; NaN where ``n < 3``.
    n : (K,) int64
        Rows in the window.
    sigma : (K,) float64
        The residual standard deviation ``s`` (px), an estimate of the position noise.
    """

    slope: FloatArray
    se: FloatArray
    n: IntArray
    sigma: FloatArray


def _offsets(frame: IntArray, track_id: IntArray, half: int):  # type: ignore[no-untyped-def]
    """Yield ``(lo, hi, ok)`` for every offset ``o = 1 .. half``: the row pairs ``(i, i + o)``
    as the slices ``lo = [0, K - o)`` and ``hi = [o, K)``, and whether the two rows belong to
    the same track within ``half`` frames of each other. Windows are symmetric, so each pair
    serves both of its rows."""
    k = frame.shape[0]
    for o in range(1, min(half, max(k - 1, 0)) + 1):
        lo, hi = slice(0, k - o), slice(o, k)
        ok = (track_id[hi] == track_id[lo]) & (frame[hi] - frame[lo] <= half)
        yield lo, hi, ok


def local_fit(
    frame: IntArray, track_id: IntArray, xy: FloatArray, half: int,
    weight: BoolArray | None = None,
) -> LocalFit:
    """Least-squares line through each row's window of ``± half`` frames of its track.

    Rows must be sorted by track, then frame. ``weight`` (K,) selects the rows that enter the
    fits (e.g. measured rows only); every row still gets a fit from its neighbours. Sums are
    accumulated relative to row ``i`` (``t - t_i``, ``x - x_i``), so frame numbers and image
    coordinates of any size keep full precision.
    """
    k = frame.shape[0]
    use = np.ones(k, bool) if weight is None else np.asarray(weight, bool)
    use = use & np.isfinite(xy).all(axis=1)
    x = np.where(use, xy[:, 0], 0.0)
    y = np.where(use, xy[:, 1], 0.0)
    f = frame.astype(np.float64)
    w0 = use.astype(np.float64)
    n, st, stt = w0.copy(), np.zeros(k), np.zeros(k)
    sx, sy, stx, sty, sxx = (np.zeros(k) for _ in range(5))
    for lo, hi, ok in _offsets(frame, track_id, half):
        dt = f[hi] - f[lo]
        dx = x[hi] - x[lo]
        dy = y[hi] - y[lo]
        dd = dx * dx + dy * dy
        for a, b in ((lo, hi), (hi, lo)):  # row a gains its neighbour b (sign of dt, dx flips)
            w = ok & use[b]
            sgn = 1.0 if a is lo else -1.0
            wf = w.astype(np.float64)
            n[a] += wf
            st[a] += sgn * dt * wf
            stt[a] += dt * dt * wf
            sx[a] += sgn * dx * wf
            sy[a] += sgn * dy * wf
            stx[a] += dt * dx * wf
            sty[a] += dt * dy * wf
            sxx[a] += dd * wf
    with np.errstate(invalid="ignore", divide="ignore"):
        nn = np.maximum(n, 1)
        sdd = stt - st * st / nn  # Σ (t - t̄)²
        bx = (stx - st * sx / nn) / sdd
        by = (sty - st * sy / nn) / sdd
        # RSS = Σ (x - x̄)² - b² Σ (t - t̄)², summed over both axes
        rss = sxx - (sx * sx + sy * sy) / nn - (bx * bx + by * by) * sdd
        s2 = np.maximum(rss, 0.0) / (2.0 * (n - 2))
        se = np.sqrt(s2 / sdd)
    b = np.column_stack([bx, by])
    b[~(sdd > 0)] = np.nan
    se[n < 3] = np.nan
    return LocalFit(b, se, n.astype(np.int64), np.where(n >= 3, np.sqrt(s2), np.nan))


def local_mean(
    frame: IntArray, track_id: IntArray, values: FloatArray, half: int,
) -> tuple[FloatArray, IntArray]:
    """Mean of ``values`` (K, d) over each row's window of ``± half`` frames of its track
    (rows with a NaN left out), and the number of rows averaged."""
    vals = np.asarray(values, np.float64).reshape(values.shape[0], -1)
    finite = np.isfinite(vals).all(axis=1)
    base = np.where(finite[:, None], vals, 0.0)
    cols = [base[:, c].copy() for c in range(base.shape[1])]
    acc = [c.copy() for c in cols]
    cnt = finite.astype(np.float64)
    for lo, hi, ok in _offsets(frame, track_id, half):
        for a, b in ((lo, hi), (hi, lo)):
            w = (ok & finite[b]).astype(np.float64)
            cnt[a] += w
            for c in range(len(cols)):
                acc[c][a] += cols[c][b] * w
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.column_stack(acc) / cnt[:, None]
    return mean.reshape(values.shape), cnt.astype(np.int64)
