"""The X9 scene of paper 3 (SPEC §5 X9): a three-part walker passing behind a desk.

320×240 pixels, 150 frames, an achromatic wall with a door zone (x ∈ [0, 60], y ∈ [80, 200]).
The walker is a vertical chain of three coloured parts touching at y = 112 and y = 142:

======  ===============  =====  ========
part    shape (w × h)    hue    centre y
======  ===============  =====  ========
head    ellipse 10 × 12  30°    106 (bobs ±1 px)
torso   box 16 × 30      210°   127
legs    box 14 × 34      120°   159
======  ===============  =====  ========

The centre x is 20 + 2t; the legs swing by 2 sin(2π(t − 126)/16) px. An achromatic desk at
x ∈ [262, 282], y ∈ [142, 215] is drawn over the legs, which are partly hidden for t ≈ 118–134
and fully hidden for t = 125–127. A pixel (u, v) belongs to a shape when its centre
(u + ½, v + ½) does, so the full boxes always hold 14 × 34 pixels and the true centre is the
geometric centre.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

__all__ = ["DESK", "DOOR", "HUES", "OcclusionScene", "render_occlusion_scene"]

#: desk rectangle x0, y0, x1, y1 (pixels)
DESK = (262.0, 142.0, 282.0, 215.0)
#: detection zone near the door x0, y0, x1, y1
DOOR = (0.0, 80.0, 60.0, 200.0)
#: part hues in degrees: head, torso, legs
HUES = (30.0, 210.0, 120.0)
#: part sizes (w, h)
SIZES = ((10.0, 12.0), (16.0, 30.0), (14.0, 34.0))
#: part centre y
CENTRE_Y = (106.0, 127.0, 159.0)


@dataclass(frozen=True)
class OcclusionScene:
    """Rendered X9 sequence with ground truth.

    Attributes
    ----------
    frames : uint8 (T, H, W, 3)
        BGR images.
    labels : int8 (T, H, W)
        Visible part of every pixel: 0 background/desk, 1 head, 2 torso, 3 legs.
    centres : (T, 3, 2)
        True (unoccluded) part centres.
    sizes : (3, 2)
        Part sizes w, h.
    desk, door : tuple
        Rectangles x0, y0, x1, y1.
    hues : tuple
        Part hues (degrees).
    """

    frames: NDArray[np.uint8]
    labels: NDArray[np.int8]
    centres: FloatArray
    sizes: FloatArray
    desk: tuple[float, float, float, float]
    door: tuple[float, float, float, float]
    hues: tuple[float, float, float]

    @property
    def boxes(self) -> FloatArray:
        """True full part boxes (T, 3, 4) as x0, y0, x1, y1."""
        half = self.sizes[None] / 2.0
        return np.concatenate([self.centres - half, self.centres + half], axis=-1)


def _hsv_bgr(hue_deg: float, sat: float, val: float) -> NDArray[np.float64]:
    hsv = np.array([[[hue_deg / 2.0, sat * 255.0, val * 255.0]]], dtype=np.float32)
    return cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2BGR)[0, 0].astype(float)


def render_occlusion_scene(
    *,
    n_frames: int = 150,
    size: tuple[int, int] = (320, 240),
    noise: float = 2.0,
    seed: int = 0,
) -> OcclusionScene:
    """Render the X9 scene.

    Parameters
    ----------
    n_frames : int
        Number of frames T (150 in SPEC X9).
    size : (W, H)
        Image size.
    noise : float
        Standard deviation of the Gaussian sensor noise added to every channel (grey levels).
    seed : int
        Seed of the noise generator.
    """
    if n_frames < 1:
        raise ValueError(f"n_frames must be >= 1, got {n_frames}")
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    W, H = size
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames, dtype=float)
    cx = 20.0 + 2.0 * t
    head_y = CENTRE_Y[0] + np.sin(2 * np.pi * t / 16.0)  # the head bobs ±1 px
    legs_x = cx + 2.0 * np.sin(2 * np.pi * (t - 126.0) / 16.0)
    centres = np.stack(
        [
            np.stack([cx, head_y], axis=1),
            np.stack([cx, np.full_like(t, CENTRE_Y[1])], axis=1),
            np.stack([legs_x, np.full_like(t, CENTRE_Y[2])], axis=1),
        ],
        axis=1,
    )
    u = np.arange(W, dtype=float)[None, None, :] + 0.5
    v = np.arange(H, dtype=float)[None, :, None] + 0.5
    c = centres[:, :, None, None, :]  # (T, 3, 1, 1, 2)
    (hw, hh), (tw, th), (lw, lh) = SIZES
    head = ((u - c[:, 0, ..., 0]) / (hw / 2)) ** 2 + ((v - c[:, 0, ..., 1]) / (hh / 2)) ** 2 <= 1
    torso = (np.abs(u - c[:, 1, ..., 0]) < tw / 2) & (np.abs(v - c[:, 1, ..., 1]) < th / 2)
    legs = (np.abs(u - c[:, 2, ..., 0]) < lw / 2) & (np.abs(v - c[:, 2, ..., 1]) < lh / 2)
    x0, y0, x1, y1 = DESK
    desk = (u >= x0) & (u <= x1) & (v >= y0) & (v <= y1)
    labels = np.zeros((n_frames, H, W), dtype=np.int8)
    labels[head] = 1
    labels[torso] = 2  # drawn over the head's lowest row where the head bobs down
    labels[legs] = 3
    labels[np.broadcast_to(desk, labels.shape)] = 0  # the desk hides the legs only

    img = np.full((n_frames, H, W, 3), 150.0)
    dx0, dy0, dx1, dy1 = DOOR
    door = (u >= dx0) & (u <= dx1) & (v >= dy0) & (v <= dy1)
    img[np.broadcast_to(door, labels.shape)] = 125.0
    img[np.broadcast_to(desk, labels.shape)] = 90.0
    for k, hue in enumerate(HUES, start=1):
        img[labels == k] = _hsv_bgr(hue, 0.7, 0.8)
    img += rng.normal(0.0, noise, img.shape)
    frames = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    return OcclusionScene(
        frames=frames,
        labels=labels,
        centres=centres,
        sizes=np.asarray(SIZES, dtype=float),
        desk=DESK,
        door=DOOR,
        hues=HUES,
    )
