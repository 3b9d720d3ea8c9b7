"""``N`` targets at nearly constant velocity, for scale tests."""

from __future__ import annotations

import numpy as np

from mvtrack.sim.scene import Scene, assemble


# ---------------------------------------------------------------------- crowd
def crowd(
    n: int,
    frames: int = 300,
    fps: float = 30.0,
    size: tuple[int, int] = (1920, 1080),
    seed: int | np.random.Generator = 0,
    accel_sigma: float = 0.05,
    speed_range: tuple[float, float] = (1.0, 6.0),
    clamp_speed: bool = False,
) -> Scene:
    """``n`` targets moving at nearly constant velocity, for scale tests (issue 3).

    Speed uniform in ``speed_range`` (1–6 px/frame) in a uniform direction, plus white
    acceleration ``a_k ~ N(0, accel_sigma²)`` per axis: ``v_{k+1} = v_k + a_k``, ``p_{k+1} =
    p_k + v_{k+1}``, so the speed drifts as a random walk (about ±0.9 px/frame per axis after
    300 frames); ``clamp_speed=True`` keeps it inside ``speed_range`` by rescaling the
    velocity. The box is reflected elastically at the borders (position mirrored, velocity
    component reversed), so every box stays inside the image. Boxes 40×30 px, each side ±10 %
    (uniform, fixed per target). Vectorised over targets: a loop over frames only.
    """
    if n < 1:
        raise ValueError(f"n must be at least 1, got {n}")
    if frames < 1:
        raise ValueError(f"frames must be at least 1, got {frames}")
    lo_v, hi_v = speed_range
    if not 0 < lo_v <= hi_v:
        raise ValueError(f"speed_range must satisfy 0 < low <= high, got {speed_range}")
    rng = np.random.default_rng(seed)
    wh = np.array([40.0, 30.0]) * rng.uniform(0.9, 1.1, (n, 2))
    lim_lo = wh / 2
    lim_hi = np.array(size, float) - wh / 2
    if np.any(lim_hi <= lim_lo):
        raise ValueError(f"size {size} is too small for 40×30 px boxes")
    p = rng.uniform(lim_lo, lim_hi)
    ang = rng.uniform(0, 2 * np.pi, n)
    spd = rng.uniform(lo_v, hi_v, n)
    v = spd[:, None] * np.stack([np.cos(ang), np.sin(ang)], -1)
    xy = np.empty((frames, n, 2))
    vel = np.empty((frames, n, 2))
    xy[0], vel[0] = p, v
    for k in range(1, frames):  # loop over frames, vectorised over targets
        v = v + accel_sigma * rng.standard_normal((n, 2))
        if clamp_speed:
            s = np.linalg.norm(v, axis=1)
            v *= (np.clip(s, lo_v, hi_v) / np.maximum(s, 1e-12))[:, None]
        p = p + v
        low, high = p < lim_lo, p > lim_hi  # elastic reflection at the borders
        p = np.where(low, 2 * lim_lo - p, np.where(high, 2 * lim_hi - p, p))
        v = np.where(low | high, -v, v)
        xy[k], vel[k] = p, v
    hd = np.arctan2(vel[..., 1], vel[..., 0])
    color = rng.integers(0, 256, (n, 3)).astype(np.uint8)
    return assemble(
        "crowd", fps, size, xy, hd, category=["target"] * n, kind=["box"] * n, body=wh,
        rotates=np.zeros(n, bool), color=color,
    )
