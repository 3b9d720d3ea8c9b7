"""The reconstructed 4-way intersection of paper 1 (SPEC X5): its roads, paths and vehicles."""

from __future__ import annotations

from typing import Any

import numpy as np

from mvtrack.sim.paths import Path2D, local_path, place
from mvtrack.sim.scene import FloatArray, IntArray, Scene, assemble

# ---------------------------------------------------------------------- X5
#: Centre of the X5 intersection, half-width of its roads and the lane offset (right-hand
#: traffic, one lane per direction).
X5_CENTRE = (160.0, 120.0)
X5_ROAD_HALF = 30.0
X5_LANE = 15.0
#: Front of a waiting vehicle, as a distance from the intersection centre along its approach.
X5_STOP = 34.0
#: Car colours (BGR) with luma ≤ 38 or ≥ 138: ≥ 50 grey levels from the asphalt (≈ 88).
X5_COLORS = np.array(
    [
        [240, 240, 240],  # white
        [200, 200, 200],  # silver
        [40, 220, 240],  # yellow
        [25, 25, 25],  # black
        [90, 30, 20],  # navy
        [240, 200, 120],  # light blue
        [0, 150, 255],  # orange
        [170, 210, 230],  # beige
        [120, 120, 255],  # light red
        [20, 10, 80],  # maroon
    ],
    dtype=np.uint8,
)
_X5_MIN_GAP = 24.0  # minimum centre distance between any two vehicles at any frame


def x5_path(approach: int, maneuver: str, size: tuple[int, int] = (320, 240)) -> Path2D:
    """Path of an X5 vehicle.

    Parameters
    ----------
    approach : int
        Direction of travel on entry: 0 eastbound, 1 southbound, 2 westbound, 3 northbound
        (the entry lane is the right-hand one, 15 px right of the road's centre line).
    maneuver : {"straight", "left", "right"}
        Left turns follow a 40 px arc, right turns a 15 px arc (SPEC X5).
    """
    theta = approach * np.pi / 2
    half = (size[0] / 2 + 20.0, size[1] / 2 + 20.0)  # start/end just off the image
    d_in = half[approach % 2]
    d_cross = half[1 - approach % 2]
    lane, road = X5_LANE, X5_ROAD_HALF
    # Local frame: travel along +x, the entry lane at y = +15, origin at the centre.
    if maneuver == "straight":
        segs: list[tuple[Any, ...]] = [("line", (-d_in, lane), (d_in, lane))]
    elif maneuver == "left":
        r = 40.0
        cx = lane - r  # -25: the arc ends on the crossing road's far lane (x = +15)
        segs = [
            ("line", (-d_in, lane), (cx, lane)),
            ("arc", (cx, lane - r), r, np.pi / 2, -np.pi / 2),
            ("line", (lane, lane - r), (lane, -d_cross)),
        ]
    elif maneuver == "right":
        r = 15.0
        segs = [
            ("line", (-d_in, lane), (-road, lane)),
            ("arc", (-road, lane + r), r, -np.pi / 2, np.pi / 2),
            ("line", (-road + r, road), (-road + r, d_cross)),
        ]
    else:
        raise ValueError(f"maneuver must be straight, left or right, got {maneuver!r}")
    return local_path(segs, theta, X5_CENTRE)


def _waiting_profile(
    t: FloatArray, v: float, s_stop: float, t_stop: float = 60.0, t_go: float = 300.0,
    ramp: float = 20.0,
) -> FloatArray:
    """Arc length of a vehicle that brakes to stand still at ``s_stop`` from ``t_stop`` to
    ``t_go`` (constant deceleration over the last ``ramp`` px), then pulls away."""
    td = 2 * ramp / v
    s = np.where(
        t < t_stop - td,
        s_stop - ramp - v * (t_stop - td - t),
        s_stop - v / (2 * td) * (t_stop - t) ** 2,
    )
    s = np.where(t >= t_stop, s_stop, s)
    s = np.where(t > t_go, s_stop + v / (2 * td) * (t - t_go) ** 2, s)
    return np.where(t > t_go + td, s_stop + ramp + v * (t - t_go - td), s)


def _x5_place(
    rng: np.random.Generator,
    plan: list[tuple[str, str, list[int]]],
    body: FloatArray,
    t: FloatArray,
) -> tuple[FloatArray, FloatArray, IntArray, FloatArray, FloatArray] | None:
    """Rejection-sample approach, entry and speed of each vehicle in turn (None: stuck)."""
    n, n_frames = len(plan), t.shape[0]
    xy = np.full((n_frames, n, 2), np.nan)
    hd = np.zeros((n_frames, n))
    approaches = np.zeros(n, np.int64)
    entry, speed = np.zeros(n), np.zeros(n)
    for i, (cat, man, allowed) in enumerate(plan):
        for _attempt in range(400):
            a = int(rng.choice(allowed))
            v = float(rng.uniform(1.5, 3.0))
            path = x5_path(a, man)
            if cat == "waiting":
                d_in = (160.0 + 20.0) if a % 2 == 0 else (120.0 + 20.0)
                s = _waiting_profile(t, v, d_in - X5_STOP - body[i, 0] / 2)
                t0 = float(t[np.argmax(s >= 0)]) if np.any(s >= 0) else 0.0
            else:
                # entries over frames 0–300 (SPEC X5), but late enough only if the vehicle
                # still leaves the image by the last frame: every movement is complete in the
                # video, as the paper's counts by movement need
                last = min(300.0, float(n_frames - 1) - float(path.lengths.sum()) / v)
                if last < 0.0:
                    continue
                t0 = float(rng.uniform(0.0, last))
                s = v * (t - t0)
            p, h = place(path, s)
            if i:
                d = np.linalg.norm(xy[:, :i] - p[:, None], axis=-1)
                if np.any(d[np.isfinite(d)] < _X5_MIN_GAP):
                    continue
            xy[:, i], hd[:, i] = p, h
            approaches[i], entry[i], speed[i] = a, t0, v
            break
        else:
            return None
    return xy, hd, approaches, entry, speed


def x5_intersection(seed: int | np.random.Generator = 0) -> Scene:
    """The reconstructed 4-way intersection of paper 1 (SPEC X5).

    320×240, 30 fps, 360 frames; roads y ∈ [90, 150] and x ∈ [130, 190], right-hand traffic
    with one 30 px lane per direction. 20 vehicles (categories): 11 ``straight`` (6 east-west,
    5 north-south), 6 ``left`` (40 px arc), 1 ``right`` (15 px arc), 2 ``waiting`` (brake to
    the stop line, stand still from frame 60 to 300, then drive straight on). Speeds uniform
    in 1.5–3 px/frame; entries (path starts, 20 px off the image) uniform over frames 0–300,
    but no later than lets the vehicle leave the image by the last frame (359), so that every
    movement ends in the video, as paper 1's counts by movement (11 / 6 / 1 / 2) need: the
    counting module recovers them exactly from the true tracks.
    Vehicles are 14–18 × 8–10 px two-tone bodies that turn with their heading.

    Entry times and speeds are drawn by rejection: a vehicle is placed only if its centre
    stays ≥ 24 px from every vehicle already placed at every frame, so vehicles never
    overlap (a queue would need car-following, which the scene does not model).
    """
    rng = np.random.default_rng(seed)
    n_frames = 360
    t = np.arange(n_frames, dtype=np.float64)
    # The two waiting vehicles stand on one east-west and one north-south approach, so
    # each road keeps one direction free for through traffic while they wait.
    plan: list[tuple[str, str, list[int]]] = (
        [("waiting", "straight", [0, 2]), ("waiting", "straight", [1, 3])]
        + [("straight", "straight", [0, 2])] * 6
        + [("straight", "straight", [1, 3])] * 5
        + [("left", "left", [0, 1, 2, 3])] * 6
        + [("right", "right", [0, 1, 2, 3])]
    )
    n = len(plan)
    body = np.column_stack([rng.uniform(14, 18, n), rng.uniform(8, 10, n)])
    for _restart in range(50):
        placed = _x5_place(rng, plan, body, t)
        if placed is not None:
            break
    else:  # pragma: no cover - the geometry leaves ample room
        raise RuntimeError("x5_intersection: could not place the vehicles without overlap")
    xy, hd, approaches, entry, speed = placed
    color = X5_COLORS[rng.integers(0, len(X5_COLORS), n)]
    return assemble(
        "x5", 30, (320, 240), xy, hd, category=[p[0] for p in plan], kind=["vehicle"] * n,
        body=body, rotates=np.ones(n, bool), color=color,
        meta={
            "roads": {"y": (90.0, 150.0), "x": (130.0, 190.0)},
            "centre": X5_CENTRE,
            "approach": approaches,
            "entry": entry,
            "speed": speed,
            "poles": [(112.0, 72.0), (208.0, 72.0), (112.0, 168.0), (208.0, 168.0),
                      (40.0, 80.0), (280.0, 160.0)],
        },
    )
