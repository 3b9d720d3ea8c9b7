"""Turning movements: origin and destination approach of every track.

Approaches are zones on the arms of an intersection. For each track, the visits to the
approaches (:func:`~mvtrack.analytics.zones.zone_visits`) give its origin (the first) and its
destination (the last). A track lost (or born) mid-intersection, outside every approach, is
*completed from its filtered heading*: from its last (first) position it is carried on with
its speed, heading and turn rate (the mean velocity over the last (first) ``window``
seconds, and the change of its direction over the window before), the turn capped at
``max_turn``, forwards (backwards) for at most ``horizon`` seconds; the first other approach
that the path enters is taken, and the track is marked ``completed``. A track that ends in
an approach it has not left (a queue at the end of the video, a track lost while waiting)
has not shown where it goes, and one that cannot be completed (it stands still, or the path
meets no approach) is ``incomplete``, the unknown end named :data:`UNKNOWN`: it is reported,
never dropped.

Before any of this, the fragments of one object's track are joined (:func:`join_fragments`):
a tracker that loses an object for a few frames and restarts it would otherwise count it twice,
each piece completed along its own heading (a turn read as two straight movements).

With a single visit, whether it is the origin or the destination follows from where the
track is there: born in it (origin), ended in it (destination), or else from the direction
of travel relative to the intersection centre (towards it: origin).

The turn of a movement is the signed angle from the inbound direction
``c - centroid(origin)`` to the outbound direction ``centroid(destination) - c``, with ``c``
the intersection centre: ``straight`` within ±45°, ``right`` for +45°…+135° (clockwise on the
screen, image y down), ``left`` for −45°…−135°, else ``u-turn``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.analytics.tracks import TrackPoints, local_mean
from mvtrack.analytics.zones import Zone, zone_visits
from mvtrack.association.assign import assign
from mvtrack.fragments import chain_heads, starts_between

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

UNKNOWN = "unknown"
TURNS = ("straight", "left", "right", "u-turn")
STATUSES = ("complete", "completed", "incomplete")


@dataclass(frozen=True)
class MovementSettings:
    """Attributes
    ----------
    horizon : float
        Longest extrapolation along the heading, seconds.
    window : float
        Seconds at each end of a track whose velocities give its heading.
    gap : float
        Seconds outside an approach that do not end a visit to it.
    min_speed : float
        Slowest heading, px/frame, that is extrapolated.
    max_turn : float
        Largest change of heading along an extrapolated path, degrees.
    centre : (2,) float64 or None
        Intersection centre, px (default: the mean of the approaches' centroids).
    join : float
        Longest gap, seconds, between a track's end and another's start that
        :func:`join_fragments` bridges (0: tracks are never joined).
    join_radius : float
        How far, in box sizes, the start of the next fragment may lie from where the end of
        the first one leads (and the reverse) for them to be joined.
    """

    horizon: float = 3.0
    window: float = 0.25
    gap: float = 0.5
    min_speed: float = 0.2
    max_turn: float = 100.0
    centre: tuple[float, float] | None = None
    join: float = 0.5
    join_radius: float = 1.0


@dataclass(frozen=True)
class TrackMovements:
    """One row per track (order of :attr:`TrackPoints.ids`).

    ``origin`` / ``destination`` are approach indices (-1: unknown); ``origin_completed`` /
    ``destination_completed`` say which end was completed from the heading; ``frame`` is the
    frame at which the track left its origin (its first frame when the origin was completed),
    which puts it in a time interval.
    """

    track_id: IntArray
    origin: IntArray
    destination: IntArray
    origin_completed: NDArray[np.bool_]
    destination_completed: NDArray[np.bool_]
    frame: IntArray
    names: tuple[str, ...]
    turn_of: dict[tuple[int, int], str]

    @property
    def status(self) -> NDArray[np.str_]:
        """(T,) ``complete``, ``completed`` or ``incomplete``."""
        known = (self.origin >= 0) & (self.destination >= 0)
        ext = self.origin_completed | self.destination_completed
        return np.where(~known, "incomplete", np.where(ext, "completed", "complete"))

    def label(self, index: IntArray) -> NDArray[np.str_]:
        """Approach names of indices (``unknown`` for -1)."""
        names = np.array([*self.names, UNKNOWN])
        return names[np.where(index >= 0, index, len(self.names))]

    @property
    def turn(self) -> NDArray[np.str_]:
        """(T,) the turn of each movement ('' when an end is unknown)."""
        out = np.full(self.track_id.shape[0], "", dtype=object)
        for (o, d), name in self.turn_of.items():  # a few approach pairs
            out[(self.origin == o) & (self.destination == d)] = name
        return out.astype(str)


def join_fragments(
    tracks: TrackPoints, fps: float, settings: MovementSettings | None = None,
) -> tuple[TrackPoints, dict[int, int]]:
    """Join the fragments of one object's track before anything is counted.

    A tracker that loses an object for a few frames (a turn it did not follow, a start after
    a stand) ends its track and starts another: counted apart, each fragment is a movement of
    its own, its missing end completed from its heading. Here the track ``b`` that starts
    ``1 .. join · fps`` frames after track ``a`` ends continues ``a`` when each end leads to
    the other: ``a``'s last position carried on with its mean velocity (over the ``window``)
    for the gap lands within ``join_radius`` box sizes of ``b``'s first, and ``b``'s first
    carried back with its velocity lands as near ``a``'s last, and, where both move, the
    heading turns by at most ``max_turn`` from one to the other. The pairs are taken one to one,
    nearest first; ``b``'s rows then carry ``a``'s ID (chains of fragments the first one's).
    Tracks that overlap in time are never joined: they are two objects.

    Returns the joined rows and ``{joined ID: ID it now carries}``.
    """
    st = MovementSettings() if settings is None else settings
    g = round(st.join * fps)
    t_n = tracks.n_tracks
    if g < 1 or t_n < 2:
        return tracks, {}
    start_row, end_row = tracks.starts[:-1], tracks.starts[1:] - 1
    half = max(1, round(st.window * fps))
    vmean, _ = local_mean(tracks.frame, tracks.track_id, tracks.velocity, half)
    vmean = np.nan_to_num(vmean)
    f_end, f_start = tracks.frame[end_row], tracks.frame[start_row]
    a, b = starts_between(f_start, f_end + 1, f_end + g)
    if a.size == 0:
        return tracks, {}
    dt = (f_start[b] - f_end[a]).astype(np.float64)[:, None]
    pa, pb = tracks.xy[end_row[a]], tracks.xy[start_row[b]]
    fwd = np.linalg.norm(pb - (pa + vmean[end_row[a]] * dt), axis=1)
    bwd = np.linalg.norm(pa - (pb - vmean[start_row[b]] * dt), axis=1)
    size = np.maximum(tracks.wh[end_row[a]].max(axis=1), tracks.wh[start_row[b]].max(axis=1))
    cost = np.maximum(fwd, bwd) / np.maximum(size, 1e-9)
    # where both move, the heading may not turn by more than max_turn across the gap
    va, vb = vmean[end_row[a]], vmean[start_row[b]]
    sa, sb = np.hypot(va[:, 0], va[:, 1]), np.hypot(vb[:, 0], vb[:, 1])
    moving = (sa >= st.min_speed) & (sb >= st.min_speed)
    cos = np.einsum("ti,ti->t", va, vb) / np.maximum(sa * sb, 1e-12)
    ok = (cost <= st.join_radius) & (~moving | (cos >= np.cos(np.radians(st.max_turn))))
    pairs = assign(a[ok], b[ok], cost[ok], t_n, t_n, "greedy")  # one to one, nearest first
    if pairs.track.size == 0:
        return tracks, {}
    parent = np.arange(t_n)
    parent[pairs.det] = pairs.track
    head = chain_heads(parent)
    ids = tracks.ids
    new_id = ids[head][tracks.track_index]
    order = np.lexsort((tracks.frame, new_id))
    joined = TrackPoints(
        tracks.frame[order], new_id[order], tracks.xy[order], tracks.wh[order],
        tracks.velocity[order], tracks.measured_xy[order], tracks.state[order],
        tracks.cls[order], tracks.velocity_source,
    )
    moved = np.flatnonzero(head != np.arange(t_n))
    return joined, {int(ids[t]): int(ids[head[t]]) for t in moved.tolist()}


def turn_table(approaches: list[Zone], centre: FloatArray | None = None) -> dict[
        tuple[int, int], str]:
    """The turn of every (origin, destination) pair of approaches (module docstring)."""
    cen = np.array([z.centroid for z in approaches])
    c = cen.mean(axis=0) if centre is None else np.asarray(centre, float)
    out = {}
    for o in range(len(approaches)):
        for d in range(len(approaches)):
            a, b = c - cen[o], cen[d] - c
            ang = np.degrees(np.arctan2(a[0] * b[1] - a[1] * b[0], a @ b))
            if o == d or abs(ang) > 135.0:
                name = "u-turn"
            elif abs(ang) <= 45.0:
                name = "straight"
            else:
                name = "right" if ang > 0 else "left"
            out[o, d] = name
    return out


def _first_hit(
    start: FloatArray, vel: FloatArray, omega: FloatArray, approaches: list[Zone],
    exclude: IntArray, steps: int, max_turn: float,
) -> IntArray:
    """For the paths of constant speed and turn rate from ``start`` (T, 2) with velocity
    ``vel`` (T, 2, px/frame) and turn rate ``omega`` (T, rad/frame), sampled over
    ``t = 1 .. steps`` frames, the first approach each enters other than ``exclude``
    (-1: none). The heading turns by at most ``max_turn`` rad, then goes straight on.
    """
    t_n = start.shape[0]
    if t_n == 0 or steps < 1:
        return np.full(t_n, -1, np.int64)
    ts = np.linspace(1.0, float(steps), min(steps, 60))[None, :]  # (1, S)
    speed = np.hypot(vel[:, 0], vel[:, 1])[:, None]
    th0 = np.arctan2(vel[:, 1], vel[:, 0])[:, None]
    om = omega[:, None]
    t_turn = np.where(np.abs(om) > 1e-9, max_turn / np.maximum(np.abs(om), 1e-9), np.inf)
    tc = np.minimum(ts, t_turn)  # time spent turning
    with np.errstate(invalid="ignore", divide="ignore"):
        arc_x = np.where(np.abs(om) > 1e-9, (np.sin(th0 + om * tc) - np.sin(th0)) / om,
                         np.cos(th0) * tc)
        arc_y = np.where(np.abs(om) > 1e-9, (np.cos(th0) - np.cos(th0 + om * tc)) / om,
                         np.sin(th0) * tc)
    th1 = th0 + om * tc
    rest = ts - tc
    px = start[:, :1] + speed * (arc_x + np.cos(th1) * rest)
    py = start[:, 1:] + speed * (arc_y + np.sin(th1) * rest)
    flat = np.column_stack([px.ravel(), py.ravel()])
    n_s = ts.shape[1]
    first = np.full(t_n, n_s, np.int64)
    hit = np.full(t_n, -1, np.int64)
    for a, zone in enumerate(approaches):  # a handful of approaches
        inside = zone.contains(flat).reshape(t_n, n_s) & (exclude != a)[:, None]
        where = np.where(inside.any(axis=1), inside.argmax(axis=1), n_s)
        better = where < first
        first = np.where(better, where, first)
        hit = np.where(better, a, hit)
    return hit


def _turn_rate(v_a: FloatArray, v_b: FloatArray, frames: FloatArray) -> FloatArray:
    """Mean turn rate (rad/frame) from velocity ``v_a`` to ``v_b`` over ``frames``."""
    d = np.arctan2(v_a[:, 0] * v_b[:, 1] - v_a[:, 1] * v_b[:, 0],
                   np.einsum("ti,ti->t", v_a, v_b))
    return np.where(frames > 0, d / np.maximum(frames, 1), 0.0)


def track_movements(
    tracks: TrackPoints, approaches: list[Zone], fps: float, anchor: str = "centre",
    settings: MovementSettings | None = None,
) -> TrackMovements:
    """Origin, destination and status of every track (module docstring)."""
    st = MovementSettings() if settings is None else settings
    t_n = tracks.n_tracks
    names = tuple(z.name for z in approaches)
    turns = turn_table(approaches, None if st.centre is None else np.asarray(st.centre))
    if t_n == 0 or not approaches:
        z = np.full(t_n, -1, np.int64)
        f = np.zeros(t_n, bool)
        return TrackMovements(tracks.ids, z, z.copy(), f, f.copy(),
                              tracks.frame[tracks.starts[:-1]], names, turns)
    p = tracks.anchor(anchor)
    gap = round(st.gap * fps)
    # every visit to every approach, then sorted by track and time
    parts = []
    for a, zone in enumerate(approaches):  # a handful of approaches, vectorised over rows
        v = zone_visits(zone.contains(p), tracks, gap)
        parts.append(np.column_stack([v.track_id, v.first, v.last, v.first_row, v.last_row,
                                      np.full(len(v), a)]))
    vis = np.concatenate(parts).astype(np.int64)
    vis = vis[np.lexsort((vis[:, 1], vis[:, 0]))]
    t_of = np.searchsorted(tracks.ids, vis[:, 0])
    n_vis = np.bincount(t_of, minlength=t_n)
    # visits are sorted by track: each track's first and last visit bound its block
    block = np.concatenate([[0], np.cumsum(n_vis)])
    first_v = np.where(n_vis > 0, block[:-1], -1)
    last_v = np.where(n_vis > 0, block[1:] - 1, -1)

    start_row, end_row = tracks.starts[:-1], tracks.starts[1:] - 1
    # heading at each end: mean velocity over the first / last `window` seconds
    half = max(1, round(st.window * fps))
    vmean, _ = local_mean(tracks.frame, tracks.track_id, tracks.velocity, half)
    v_end = np.nan_to_num(vmean[end_row])
    v_start = np.nan_to_num(vmean[start_row])

    origin = np.full(t_n, -1, np.int64)
    dest = np.full(t_n, -1, np.int64)
    two = n_vis >= 2
    origin[two] = vis[first_v[two], 5]
    dest[two] = vis[last_v[two], 5]
    origin_frame = np.where(two, vis[np.maximum(first_v, 0), 2], tracks.frame[start_row])

    one = n_vis == 1
    j = np.maximum(first_v, 0)
    born_in = one & (vis[j, 3] == start_row)
    ends_in = one & (vis[j, 4] == end_row)
    cen = np.array([z.centroid for z in approaches])
    centre = cen.mean(axis=0) if st.centre is None else np.asarray(st.centre, float)
    inward = np.einsum("ti,ti->t", p[end_row] - p[start_row],
                       centre - cen[vis[j, 5]]) >= 0
    as_origin = one & ((born_in & ~ends_in) | (~(born_in ^ ends_in) & inward))
    as_dest = one & ~as_origin
    origin[as_origin] = vis[j[as_origin], 5]
    origin_frame = np.where(as_origin, vis[j, 2], origin_frame)
    dest[as_dest] = vis[j[as_dest], 5]

    # complete an end from the heading only where the track was lost (or born) outside
    # every approach: mid-intersection. A track that ends in an approach has not shown where
    # it goes (or came from): it stays incomplete.
    in_any_end = np.zeros(t_n, bool)
    in_any_start = np.zeros(t_n, bool)
    for zone in approaches:
        in_any_end |= zone.contains(p[end_row])
        in_any_start |= zone.contains(p[start_row])
    steps = round(st.horizon * fps)
    max_turn = np.radians(st.max_turn)
    # heading and turn rate at each end, from the smoothed velocity one window apart
    inner_end = np.maximum(end_row - half, start_row)
    inner_start = np.minimum(start_row + half, end_row)
    v_in_e = np.nan_to_num(vmean[inner_end])
    v_in_s = np.nan_to_num(vmean[inner_start])
    span_e = (tracks.frame[end_row] - tracks.frame[inner_end]).astype(np.float64)
    span_s = (tracks.frame[inner_start] - tracks.frame[start_row]).astype(np.float64)
    om_e = _turn_rate(v_in_e, v_end, span_e)
    om_s = _turn_rate(v_start, v_in_s, span_s)
    need_d = dest < 0
    ok_d = need_d & ~in_any_end & (np.hypot(v_end[:, 0], v_end[:, 1]) >= st.min_speed)
    dest[ok_d] = _first_hit(p[end_row[ok_d]], v_end[ok_d], om_e[ok_d], approaches,
                            origin[ok_d], steps, max_turn)
    need_o = origin < 0
    ok_o = need_o & ~in_any_start & (np.hypot(v_start[:, 0], v_start[:, 1]) >= st.min_speed)
    # backwards: reverse the velocity; the turn then runs the other way in time
    origin[ok_o] = _first_hit(p[start_row[ok_o]], -v_start[ok_o], om_s[ok_o], approaches,
                              dest[ok_o], steps, max_turn)
    return TrackMovements(
        tracks.ids, origin, dest, need_o & (origin >= 0), need_d & (dest >= 0),
        origin_frame.astype(np.int64), names, turns,
    )
