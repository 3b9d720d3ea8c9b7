"""Paper 2's two crossing point targets (SPEC X7)."""

from __future__ import annotations

import numpy as np

from mvtrack.sim.scene import Scene, assemble


# ---------------------------------------------------------------------- X7
def x7_crossing(seed: int | np.random.Generator = 0, jitter: float = 0.0) -> Scene:
    """Paper 2's crossing point targets (SPEC X7).

    T1 from (20, 220) with v = (2.8, −2.0), T2 from (20, 120) with v = (2.8, 0); 100 frames;
    both at (160, 120) at frame 50. ``jitter`` is the along-track speed jitter: each frame's
    step is ``v (1 + jitter·ε_k)``, ε_k ~ N(0, 1), with the walk anchored at frame 50 so the
    targets still meet at (160, 120) then. Targets are drawn as 4×4 px points.
    """
    if jitter < 0:
        raise ValueError(f"jitter must be >= 0, got {jitter}")
    rng = np.random.default_rng(seed)
    n_frames = 100
    p0 = np.array([[20.0, 220.0], [20.0, 120.0]])
    v = np.array([[2.8, -2.0], [2.8, 0.0]])
    t = np.arange(n_frames, dtype=np.float64)
    eps = rng.standard_normal((n_frames, 2)) if jitter > 0 else np.zeros((n_frames, 2))
    steps = 1.0 + jitter * eps  # step k moves from frame k to k + 1 (last row unused)
    cum = np.concatenate([np.zeros((1, 2)), np.cumsum(steps[:-1], axis=0)])  # Σ_{j<k}
    tau = cum - cum[50]  # along-track "time" since frame 50, exactly 0 at frame 50
    if jitter == 0:
        tau = t[:, None] - 50.0
    xy = p0[None] + (50.0 + tau)[..., None] * v[None]
    hd = np.broadcast_to(np.arctan2(v[:, 1], v[:, 0]), (n_frames, 2)).copy()
    return assemble(
        "x7", 30, (320, 240), xy, hd, category=["T1", "T2"], kind=["point", "point"],
        body=np.full((2, 2), 4.0), rotates=np.zeros(2, bool),
        color=np.array([[255, 255, 255], [0, 255, 255]], np.uint8),
        meta={"jitter": float(jitter)},
    )
