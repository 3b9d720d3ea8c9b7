"""Paper 1's synthetic scene of nine vehicles (SPEC X4), from its exact formulas."""

from __future__ import annotations

import numpy as np

from mvtrack.sim.paths import Path2D
from mvtrack.sim.scene import Scene, assemble

# ---------------------------------------------------------------------- X4
#: X4 vehicle colours (BGR): distinct, each with |luma − 96| ≥ 60 against the grey road.
X4_COLORS = np.array(
    [
        [255, 255, 255],  # V1 white
        [0, 255, 255],  # V2 yellow
        [255, 255, 0],  # V3 cyan
        [128, 255, 128],  # V4 light green
        [203, 192, 255],  # V5 pink
        [0, 165, 255],  # V6 orange
        [0, 0, 0],  # V7 black
        [128, 0, 0],  # V8 navy
        [0, 0, 110],  # V9 dark red
    ],
    dtype=np.uint8,
)


def x9_path() -> Path2D:
    """V9's path in X4: line, arc A (r = 24), line, arc B (r = 8), line (SPEC X4)."""
    return Path2D(
        (
            ("line", (-6.0, 16.0), (100.0, 16.0)),
            ("arc", (100.0, 40.0), 24.0, -np.pi / 2, np.pi / 2),  # A: +x → +y
            ("line", (124.0, 40.0), (124.0, 50.0)),
            ("arc", (132.0, 50.0), 8.0, np.pi, -np.pi / 2),  # B: +y → +x
            ("line", (132.0, 58.0), (330.0, 58.0)),
        )
    )


def x4_nine_vehicles() -> Scene:
    """Paper 1's synthetic scene of 9 vehicles (SPEC X4), exactly.

    320×240, 30 fps, 240 frames, grey (96, 96, 96) road, 12×8 px axis-aligned vehicles.
    Centres at frame ``t``: V1–V5 ``(10 + 1.5t, 84 + 16i)``; V6 ``(6 + 2.4t, 166 + 0.6t)``;
    V7 ``(356.4 − 2.4t, 156.4 + 0.6t)``; V8 ``(314 − 1.5t, 230)``; V9 from ``t = 40`` at
    6 px/frame along :func:`x9_path`. Categories: ``side-by-side``, ``crossing``,
    ``constant``, ``fast``.
    """
    t = np.arange(240, dtype=np.float64)
    xy = np.full((240, 9, 2), np.nan)
    hd = np.zeros((240, 9))
    for i in range(5):
        xy[:, i] = np.stack([10 + 1.5 * t, np.full_like(t, 84 + 16 * i)], -1)
    xy[:, 5] = np.stack([6 + 2.4 * t, 166 + 0.6 * t], -1)
    hd[:, 5] = np.arctan2(0.6, 2.4)
    xy[:, 6] = np.stack([356.4 - 2.4 * t, 156.4 + 0.6 * t], -1)
    hd[:, 6] = np.arctan2(0.6, -2.4)
    xy[:, 7] = np.stack([314 - 1.5 * t, np.full_like(t, 230.0)], -1)
    hd[:, 7] = np.pi
    on = t >= 40
    p, h = x9_path().at(6.0 * (t[on] - 40))
    xy[on, 8] = p
    hd[on, 8] = h
    return assemble(
        "x4", 30, (320, 240), xy, hd,
        category=["side-by-side"] * 5 + ["crossing"] * 2 + ["constant", "fast"],
        kind=["block"] * 9, body=np.tile([12.0, 8.0], (9, 1)), rotates=np.zeros(9, bool),
        color=X4_COLORS, color2=X4_COLORS, meta={"background": (96, 96, 96)},
    )
