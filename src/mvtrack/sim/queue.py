"""A stop-and-go queue at a signalised intersection, with its approaches and count line.

Top-down, 480×240 px at 30 fps, 1200 frames (40 s); a 4-way intersection centred at
(360, 120) with 60 px roads (one 30 px lane per direction, right-hand traffic) and 16×9 px
vehicles (about 0.25 m/px). The eastbound approach (from the west) has a red light from
frame 90 to frame 690 (20 s): eight vehicles arrive one after another, brake behind the stop
line and behind each other (car following with a 24 px spacing of centres, braking at most
0.15 px/frame², pulling away at 0.05 px/frame²), stand for about 5 to 20 s, and leave at
green one after another, 5 straight on, 2 turning left and 1 right; two more eastbound
vehicles arrive during green and pass without stopping. During the red, four vehicles
cross north–south (two each way).

``scene.meta`` holds the truth of the analytics: ``origin`` / ``destination`` per vehicle
(approach names ``W``, ``N``, ``E``, ``S``), ``stopped_frames`` per vehicle (frames standing
still), and :func:`queue_settings` gives the scene's approaches, the count line over the
eastbound stop line and the queue zone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mvtrack.sim.dense import scene_from_dense
from mvtrack.sim.intersection import X5_COLORS
from mvtrack.sim.paths import Path2D, local_path
from mvtrack.sim.scene import Scene

FloatArray = NDArray[np.float64]

SIZE = (480, 240)
CENTRE = (360.0, 120.0)
HALF, LANE, STOP = 30.0, 15.0, 34.0
BODY = (16.0, 9.0)
RED = (90, 690)
SPACING = 24.0
N_FRAMES = 1200
METRES_PER_PIXEL = 0.25
#: approach name of the direction of travel on entry (0 east, 1 south, 2 west, 3 north)
ORIGIN_NAME = ("W", "N", "E", "S")


def path(approach: int, maneuver: str) -> Path2D:
    """Path of a vehicle entering travelling ``approach`` (0 east, 1 south, 2 west, 3 north)
    and going ``straight``, ``left`` (40 px arc) or ``right`` (15 px arc)."""
    theta = approach * np.pi / 2
    c = np.array(CENTRE)
    # distance from the centre to just off the image, along and across the entry direction
    far = np.array([[c[0] + 20.0, SIZE[0] - c[0] + 20.0], [c[1] + 20.0, SIZE[1] - c[1] + 20.0]])
    d_in = far[approach % 2][0 if approach < 2 else 1]
    d_out = {"straight": far[approach % 2][1 if approach < 2 else 0]}
    if maneuver == "straight":
        segs: list[tuple[Any, ...]] = [("line", (-d_in, LANE), (d_out["straight"], LANE))]
    elif maneuver == "left":
        r = 40.0
        cx = LANE - r
        # leaving towards -y in the local frame: the image side in that direction
        d_cross = far[1 - approach % 2][0 if approach in (0, 3) else 1]
        segs = [("line", (-d_in, LANE), (cx, LANE)),
                ("arc", (cx, LANE - r), r, np.pi / 2, -np.pi / 2),
                ("line", (LANE, LANE - r), (LANE, -d_cross))]
    elif maneuver == "right":
        r = 15.0
        d_cross = far[1 - approach % 2][1 if approach in (0, 3) else 0]
        segs = [("line", (-d_in, LANE), (-HALF, LANE)),
                ("arc", (-HALF, LANE + r), r, -np.pi / 2, np.pi / 2),
                ("line", (-HALF + r, HALF), (-HALF + r, d_cross))]
    else:
        raise ValueError(f"maneuver must be straight, left or right, got {maneuver!r}")
    return local_path(segs, theta, c)


def _destination(approach: int, maneuver: str) -> str:
    """Approach name where a vehicle leaves (right-hand traffic, image y down)."""
    heading = approach + {"straight": 0, "left": -1, "right": 1}[maneuver]
    return ("E", "S", "W", "N")[heading % 4]


def queue_scene(seed: int | np.random.Generator = 0) -> Scene:
    """The stop-and-go scene (module docstring); ``seed`` draws speeds, arrival jitter,
    the order of the turning vehicles in the queue and the colours."""
    rng = np.random.default_rng(seed)
    t = np.arange(N_FRAMES)
    # eastbound: 8 queueing, then 2 during green; north-south: 4 during the red
    moves = ["straight"] * 5 + ["left"] * 2 + ["right"]
    moves = [moves[i] for i in rng.permutation(8)] + ["straight", "left"]
    arrive = np.concatenate([np.linspace(0, 430, 8), [760.0, 830.0]]) + rng.uniform(0, 15, 10)
    plan = [(0, m, a) for m, a in zip(moves, arrive, strict=True)]
    plan += [(1, "straight", 150.0), (3, "straight", 230.0), (1, "straight", 360.0),
             (3, "straight", 440.0)]
    n = len(plan)
    v_free = rng.uniform(1.8, 2.6, n)
    paths = [path(a, m) for a, m, _ in plan]
    s_stop = (c_d := CENTRE[0] + 20.0) - STOP - BODY[0] / 2  # centre of a car at the line
    assert c_d > 0
    s = np.full(n, -1e9)
    v = np.zeros(n)
    started = np.zeros(n, bool)
    pos = np.full((N_FRAMES, n), np.nan)
    east = np.array([a == 0 for a, _, _ in plan])
    order = np.flatnonzero(east)  # the eastbound lane, in order of arrival
    committed = np.zeros(n, bool)  # too close to the line to stop when the red begins
    brake = 0.1  # px/frame², the comfortable deceleration of the approach
    for k in t:  # car following: one step for all vehicles per frame
        go = ~started & (k >= np.array([p[2] for p in plan]))
        s[go], v[go], started[go] = 0.0, v_free[go], True
        if k == RED[0]:
            committed = east & started & ((s > s_stop) | (s_stop - s < v * v / (2 * 0.15)))
        limit = np.full(n, np.inf)
        if RED[0] <= k < RED[1]:
            limit[east & started & ~committed & (s <= s_stop)] = s_stop
        lead, foll = order[:-1], order[1:]
        shared = started[lead] & (s[lead] < s_stop + 60.0)
        limit[foll[shared]] = np.minimum(limit[foll[shared]], s[lead[shared]] - SPACING)
        room = np.maximum(limit - s, 0.0)
        want = np.minimum(v_free, np.sqrt(2 * brake * room))
        v = np.where(started, np.clip(want, np.maximum(v - 0.15, 0.0), v + 0.05), 0.0)
        v = np.minimum(v, room)
        s = np.where(started, s + v, s)
        pos[k] = np.where(started, s, np.nan)
    xy = np.full((N_FRAMES, n, 2), np.nan)
    hd = np.zeros((N_FRAMES, n))
    for i, p in enumerate(paths):  # a dozen vehicles
        ok = np.isfinite(pos[:, i]) & (pos[:, i] <= p.length)
        q, h = p.at(np.where(ok, pos[:, i], 0.0))
        xy[ok, i], hd[ok, i] = q[ok], h[ok]
    still = np.isfinite(pos) & (np.diff(pos, axis=0, prepend=np.nan) < 0.01) & np.isfinite(
        xy[..., 0])
    body = np.tile(BODY, (n, 1))
    c, s_ = np.abs(np.cos(hd)), np.abs(np.sin(hd))
    wh = np.stack([BODY[0] * c + BODY[1] * s_, BODY[0] * s_ + BODY[1] * c], axis=-1)
    color = X5_COLORS[rng.integers(0, len(X5_COLORS), n)]
    light = (X5_COLORS[:, :].astype(int).sum(axis=1) > 380)[rng.integers(0, 1, n)]
    color2 = np.where(light[:, None], [60, 45, 40], [170, 160, 150]).astype(np.uint8)
    return scene_from_dense(
        "queue", 30.0, SIZE, xy, wh, hd,
        category=["queue" if east[i] and i < 8 else "free" for i in range(n)],
        kind=["vehicle"] * n, body=body, rotates=np.ones(n, bool), color=color, color2=color2,
        meta={
            "origin": [ORIGIN_NAME[a] for a, _, _ in plan],
            "destination": [_destination(a, m) for a, m, _ in plan],
            "maneuver": [m for _, m, _ in plan],
            "stopped_frames": still.sum(axis=0).astype(int).tolist(),
            "red": RED, "metres_per_pixel": METRES_PER_PIXEL,
        },
    )


def queue_settings() -> dict[str, Any]:
    """The ``[analytics]`` table of the scene: approaches ``W``, ``N``, ``E``, ``S`` (the
    arms outside the intersection box), the count line ``stopline`` over the eastbound lane
    (forward = eastbound), the zone ``queue`` over the eastbound lane before the line, and
    the scale."""
    cx, cy = CENTRE
    w, h = SIZE
    m = HALF + 2.0
    return {
        "interval": 10.0,
        "fps": 30.0,
        "min_frames": 10,
        "calibration": {"metres_per_pixel": METRES_PER_PIXEL},
        "approaches": {
            "W": {"polygon": [[0, cy - HALF], [cx - m, cy - HALF], [cx - m, cy + HALF],
                              [0, cy + HALF]]},
            "E": {"polygon": [[cx + m, cy - HALF], [w, cy - HALF], [w, cy + HALF],
                              [cx + m, cy + HALF]]},
            "N": {"polygon": [[cx - HALF, 0], [cx + HALF, 0], [cx + HALF, cy - m],
                              [cx - HALF, cy - m]]},
            "S": {"polygon": [[cx - HALF, cy + m], [cx + HALF, cy + m], [cx + HALF, h],
                              [cx - HALF, h]]},
        },
        "lines": {"stopline": {"points": [[cx - STOP + 4, cy + HALF], [cx - STOP + 4, cy]],
                               "hysteresis": 3.0, "labels": ["eastbound", "westbound"]}},
        "zones": {"queue": {"polygon": [[cx - STOP - 220, cy], [cx - STOP + 4, cy],
                                        [cx - STOP + 4, cy + HALF],
                                        [cx - STOP - 220, cy + HALF]]}},
    }
