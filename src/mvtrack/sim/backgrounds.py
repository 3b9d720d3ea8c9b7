"""The static picture of a simulated scene, drawn once per video.

Flat grey for X4 as SPEC X4 prescribes; asphalt roads with lane markings, stop lines and
bright roadside poles on textured ground for X5; paving for X8; asphalt for the others. Parked
occluders (X8's white car) are part of it. :func:`render_background` is the empty scene as
:func:`~mvtrack.sim.render.render_frames` draws it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.sim.drawing import ONE, SHIFT, draw_vehicle, fill_poly
from mvtrack.sim.intersection import X5_CENTRE, X5_LANE, X5_ROAD_HALF, X5_STOP
from mvtrack.sim.scene import Scene
from mvtrack.sim.style import RenderStyle, default_style

Frame = NDArray[np.uint8]


def _texture(rng: np.random.Generator, h: int, w: int, amp: float) -> NDArray[np.float32]:
    """Grey-level texture: smooth blotches plus fine grain, amplitude ``amp``."""
    if amp <= 0:
        return np.zeros((h, w), np.float32)
    coarse = rng.standard_normal((h // 12 + 2, w // 12 + 2)).astype(np.float32)
    blotch = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    grain = rng.standard_normal((h, w)).astype(np.float32)
    return amp * (0.8 * blotch + 0.5 * grain)


def _fill(base: tuple[int, int, int], tex: NDArray[np.float32]) -> Frame:
    """A picture of colour ``base`` with the grey-level texture ``tex`` added."""
    img = np.asarray(base, np.float32)[None, None, :] + tex[..., None]
    return np.clip(img + 0.5, 0, 255).astype(np.uint8)


def _intersection(
    img: Frame, rng: np.random.Generator, scene: Scene, style: RenderStyle,
    to_px: Callable[[NDArray[np.float64]], NDArray[np.float64]], scale: float,
) -> None:
    """X5: asphalt roads on grass, centre lines, edge lines, stop lines and poles."""
    h, w = img.shape[:2]
    road = _fill(style.ground, _texture(rng, h, w, style.texture))
    cx, cy = X5_CENTRE
    r = X5_ROAD_HALF
    mask = np.zeros((h, w), np.uint8)
    big = 1e4
    for x0, y0, x1, y1 in ((-big, cy - r, big, cy + r), (cx - r, -big, cx + r, big)):
        p = to_px(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
        fill_poly(mask, p, (255,))
    img[mask > 0] = road[mask > 0]
    line = (200, 205, 205)
    rot = [np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
           for a in np.arange(4) * np.pi / 2]
    c = np.array(X5_CENTRE)

    def quad(local: NDArray[np.float64], rm: NDArray[np.float64]) -> NDArray[np.float64]:
        return to_px(c + local @ rm.T)

    for rm in rot:  # each of the four arms, drawn in the eastbound frame and rotated
        far = 200.0
        for x in np.arange(-r - 8.0, -far, -14.0):  # dashed centre line
            fill_poly(img, quad(np.array([[x, -0.8], [x - 7, -0.8], [x - 7, 0.8], [x, 0.8]]), rm),
                  line)
        s = -X5_STOP + 3.0  # stop line across the incoming lane, just ahead of waiting cars
        fill_poly(img, quad(np.array([[s, 0.5], [s + 2, 0.5], [s + 2, 2 * X5_LANE - 0.5],
                                  [s, 2 * X5_LANE - 0.5]]), rm), line)
    for pole in scene.meta.get("poles", []):
        p = to_px(np.array([pole], float))[0]
        base = np.round(p * ONE).astype(np.int32)
        shadow = np.round((p + np.array([5.0, 3.0]) * scale) * ONE).astype(np.int32)
        cv2.line(img, tuple(base), tuple(shadow), (40, 50, 45), max(1, round(2 * scale)),
                 cv2.LINE_AA, SHIFT)
        cv2.circle(img, tuple(base), int(3.2 * scale * ONE), (215, 245, 250), -1,
                   cv2.LINE_AA, SHIFT)


def draw_background(scene: Scene, style: RenderStyle, size: tuple[int, int], margin: int,
                    rng: np.random.Generator) -> Frame:
    """The static picture, ``margin`` px wider on each side for camera jitter."""
    w, h = size[0] + 2 * margin, size[1] + 2 * margin
    sx, sy = size[0] / scene.size[0], size[1] / scene.size[1]

    def to_px(p: NDArray[np.float64]) -> NDArray[np.float64]:
        return p * np.array([sx, sy]) + margin

    if style.background == "flat":
        return np.full((h, w, 3), style.ground, np.uint8)
    if style.background == "intersection":
        grass = _fill((60, 105, 85), _texture(rng, h, w, 9.0))
        _intersection(grass, rng, scene, style, to_px, sx)
        img = grass
    else:
        img = _fill(style.ground, _texture(rng, h, w, style.texture))
        if style.background == "plaza":  # paving joints every 16 px
            joint = tuple(int(v) - 12 for v in style.ground)
            step = max(4, round(16 * sx))
            img[:, ::step] = joint
            img[::step, :] = joint
    for occ in scene.meta.get("occluders", []):
        draw_vehicle(img, to_px(np.array([occ["xy"]], float)), np.zeros(1),
                      np.array([occ["wh"]], float) * np.array([sx, sy]),
                      np.array([occ["color"]], np.uint8),
                      np.array([occ.get("color2", (70, 60, 55))], np.uint8))
    return img


def render_background(
    scene: Scene, seed: int | np.random.Generator = 0, size: tuple[int, int] | None = None,
    style: RenderStyle | None = None,
) -> Frame:
    """The empty scene as :func:`render_frames` draws it with the same seed (no jitter,
    no noise): the reference for "what changed" tests and examples."""
    style = default_style(scene) if style is None else style
    empty = replace(style, noise_sigma=0.0)
    out_w, out_h = scene.size if size is None else (int(size[0]), int(size[1]))
    m = int(np.ceil(style.jitter)) + 1 if style.jitter > 0 else 0
    bg = draw_background(scene, empty, (out_w, out_h), m, np.random.default_rng(seed))
    return bg[m : m + out_h, m : m + out_w].copy()
