"""A road seen in perspective, with vehicles of known speed and a known homography.

The ground plane is in metres: ``X`` along a straight four-lane road (0 at the bottom of the
picture, 80 m at the top), ``Y`` across it (lanes 3.5 m wide, centres at ±1.75 and ±5.25 m).
The camera is given by the homography that maps the road's corners ``(0, ∓7)`` and
``(80, ∓7)`` to ``(20, 470)``, ``(620, 470)``, ``(250, 60)`` and ``(390, 60)`` in a
640×480 picture (about 0.023 m/px near the camera, 0.1 m/px far from it). Vehicles keep their
lane; their speed profiles are piecewise linear in time (integrated exactly), drawn from

* ``cruise``: constant, 10–60 km/h;
* ``accelerate`` / ``brake``: from one speed in 10–60 km/h to another over 2–5 s;
* ``slow``: constant 4–8 km/h;
* ``stop-and-go``: brakes to a stand, stands 2–4 s, pulls away again.

A vehicle's box is its 1.8 m × 4.5 m footprint and 1.5 m height scaled by the local
metres-per-pixel, with its bottom centre at the image of the vehicle's ground point, so the
box's foot point maps back through the homography to the true ground position. The true
speed of every row is ``scene.meta["speed_kmh"]``, its ground point
``scene.meta["ground_xy"]``; ``scene.meta["homography"]`` maps image → ground.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.sim.dense import scene_from_dense
from mvtrack.sim.scene import Scene

FloatArray = NDArray[np.float64]

SIZE = (640, 480)
ROAD_LENGTH = 80.0
LANES = (-5.25, -1.75, 1.75, 5.25)
#: image corners of the road: (X, Y) = (0, -7), (0, 7), (80, -7), (80, 7) in metres
IMAGE_CORNERS = ((20.0, 470.0), (620.0, 470.0), (250.0, 60.0), (390.0, 60.0))
GROUND_CORNERS = ((0.0, -7.0), (0.0, 7.0), (ROAD_LENGTH, -7.0), (ROAD_LENGTH, 7.0))
KINDS = ("cruise", "accelerate", "brake", "slow", "stop-and-go")
_MIN_GAP = 9.0  # m between the ground points of two vehicles in one lane


def homography() -> FloatArray:
    """(3, 3) image → ground (m) homography of the scene."""
    import cv2

    return cv2.getPerspectiveTransform(np.float32(IMAGE_CORNERS), np.float32(GROUND_CORNERS))


def _apply(h: FloatArray, p: FloatArray) -> FloatArray:
    q = p @ h[:2, :2].T + h[:2, 2]
    w = p @ h[2, :2] + h[2, 2]
    return q / w[..., None]


def _profile(rng: np.random.Generator, kind: str, t: FloatArray, t0: float) -> FloatArray:
    """Speed (m/s) at times ``t`` (s) of a vehicle of ``kind`` entering at ``t0``."""
    kmh = 1 / 3.6
    if kind == "cruise":
        return np.full(t.shape, rng.uniform(10, 60) * kmh)
    if kind == "slow":
        return np.full(t.shape, rng.uniform(4, 8) * kmh)
    if kind in ("accelerate", "brake"):
        a, b = np.sort(rng.uniform(10, 60, 2)) * kmh
        if kind == "brake":
            a, b = b, a
        ts = t0 + rng.uniform(1.0, 3.0)
        dur = rng.uniform(2.0, 5.0)
        u = np.clip((t - ts) / dur, 0.0, 1.0)
        return a + (b - a) * u
    # stop-and-go: cruise, brake over 3 s, stand, pull away over 4 s to the same speed
    v = rng.uniform(20, 40) * kmh
    tb = t0 + rng.uniform(2.0, 4.0)
    stand = rng.uniform(2.0, 4.0)
    knots = np.array([t0 - 1e3, tb, tb + 3.0, tb + 3.0 + stand, tb + 7.0 + stand, t0 + 1e3])
    return np.interp(t, knots, [v, v, 0.0, 0.0, v, v])


def speed_scene(seed: int | np.random.Generator = 0, n_vehicles: int = 24,
                n_frames: int = 900, fps: float = 30.0) -> Scene:
    """The speed scene (module docstring): ``n_vehicles`` over ``n_frames`` at ``fps``."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / fps
    # the most constraining first: slow vehicles hold a lane for the whole scene
    mix = ["slow"] * 2 + ["stop-and-go"] * 4 + ["brake"] * 4 + ["accelerate"] * 4
    kinds = (mix + ["cruise"] * max(0, n_vehicles - len(mix)))[:n_vehicles]
    ground = np.full((n_frames, n_vehicles, 2), np.nan)
    speed = np.full((n_frames, n_vehicles), np.nan)
    lanes = np.zeros(n_vehicles, np.int64)
    for i, kind in enumerate(kinds):  # rejection sampling, one vehicle at a time
        for _attempt in range(500):
            lane = int(rng.integers(len(LANES)))
            away = LANES[lane] > 0  # right-hand traffic: +Y lanes drive away from the camera
            t0 = rng.uniform(-4.0, t[-1] * 0.8)
            v = _profile(rng, kind, t, t0)
            # exact integral of the piecewise linear speed, from the entry time on
            dist = np.concatenate([[0.0], np.cumsum((v[1:] + v[:-1]) / 2 / fps)])
            dist -= np.interp(t0, t, dist) if t0 >= 0 else -v[0] * (-t0)
            x = dist - 5.0 if away else ROAD_LENGTH + 5.0 - dist
            on = (dist >= 0) & (x > -6.0) & (x < ROAD_LENGTH + 6.0)
            if not on.any():
                continue
            p = np.where(on[:, None], np.column_stack([x, np.full(n_frames, LANES[lane])]),
                         np.nan)
            same = np.flatnonzero(lanes[:i] == lane)
            if same.size:
                d = np.abs(ground[:, same, 0] - p[:, None, 0])
                if np.any(d[np.isfinite(d)] < _MIN_GAP):
                    continue
            ground[:, i], speed[:, i], lanes[i] = p, np.where(on, v * 3.6, np.nan), lane
            break
        else:  # pragma: no cover - 80 m × 4 lanes leave room
            raise RuntimeError(f"speed_scene: could not place vehicle {i + 1}")
    h = homography()
    h_inv = np.linalg.inv(h)
    foot = _apply(h_inv, ground.reshape(-1, 2)).reshape(ground.shape)
    # local scale (px per m) from a 1 m step across the road at the ground point
    side = _apply(h_inv, (ground + np.array([0.0, 1.0])).reshape(-1, 2)).reshape(ground.shape)
    ppm = np.linalg.norm(side - foot, axis=-1)
    along = _apply(h_inv, (ground + np.array([4.5, 0.0])).reshape(-1, 2)).reshape(ground.shape)
    depth = np.abs(along[..., 1] - foot[..., 1])
    wh = np.stack([1.8 * ppm, 1.5 * ppm + depth], axis=-1)
    xy = foot - np.stack([np.zeros_like(ppm), wh[..., 1] / 2], axis=-1)
    away = np.asarray(LANES)[lanes] > 0
    heading = np.broadcast_to(np.where(away, -np.pi / 2, np.pi / 2), (n_frames, n_vehicles))
    palette = np.array([[240, 240, 240], [40, 220, 240], [25, 25, 25], [90, 30, 20],
                        [0, 150, 255], [120, 120, 255]], np.uint8)
    color = palette[rng.integers(0, len(palette), n_vehicles)]
    return scene_from_dense(
        "speed", fps, SIZE, xy, wh, heading, category=kinds, kind=["box"] * n_vehicles,
        body=np.tile([1.8, 4.5], (n_vehicles, 1)), rotates=np.zeros(n_vehicles, bool),
        color=color, color2=color, meta={"homography": h, "lanes": lanes},
        per_row={"speed_kmh": speed, "ground_xy": ground},
    )
