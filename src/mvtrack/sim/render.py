"""Synthetic traffic video: render a :class:`~mvtrack.sim.scene.Scene` to BGR frames.

Each scene gets a background drawn once (flat grey for X4 as SPEC X4 prescribes; asphalt
roads with lane markings, stop lines and bright roadside poles on textured ground for X5;
paving with the white car for X8; asphalt for the others). Per frame the renderer takes the
background shifted by the frame's camera jitter (a sub-pixel translation), draws only that
frame's objects with OpenCV (vehicles as two-tone rotated bodies with a shaded side, people as
blobs with head, torso and legs, points as dots, crowd targets as boxes), redraws occluders
over them, and adds sensor noise from a pre-drawn bank (random bank frame and offset per
frame), so a 320×240 frame costs about a millisecond.

Ground truth is in scene coordinates; camera jitter moves the picture, not the truth.

The look of a scene is :mod:`mvtrack.sim.style`, its static picture
:mod:`mvtrack.sim.backgrounds` and the drawing of its objects :mod:`mvtrack.sim.drawing`; this
module puts them together into frames (:func:`render_frames`) and a video (:func:`write_video`).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.io.atomic import atomic_path
from mvtrack.sim.backgrounds import draw_background, render_background
from mvtrack.sim.drawing import KIND_CODE, draw_block, draw_person, draw_point, draw_vehicle
from mvtrack.sim.scene import Scene
from mvtrack.sim.style import RenderStyle, default_style

__all__ = ["RenderStyle", "default_style", "render_background", "render_frames", "write_video"]

Frame = NDArray[np.uint8]


def _noise_bank(rng: np.random.Generator, size: tuple[int, int], sigma: float,
                pad: int, n_frames: int) -> tuple[list[Frame], list[Frame]]:
    """Positive and negative parts of a few pre-drawn Gaussian noise frames."""
    w, h = size[0] + pad, size[1] + pad
    count = int(np.clip(24e6 // (w * h * 3 * 4), 2, min(12, n_frames)))
    pos, neg = [], []
    for _ in range(count):
        n = np.round(sigma * rng.standard_normal((h, w, 3), dtype=np.float32))
        pos.append(np.clip(n, 0, 255).astype(np.uint8))
        neg.append(np.clip(-n, 0, 255).astype(np.uint8))
    return pos, neg


def render_frames(
    scene: Scene,
    seed: int | np.random.Generator = 0,
    size: tuple[int, int] | None = None,
    style: RenderStyle | None = None,
) -> Iterator[Frame]:
    """Yield the scene's frames as BGR ``uint8`` arrays of shape ``(H, W, 3)``.

    Parameters
    ----------
    scene : Scene
        What to draw.
    seed : int or numpy.random.Generator
        Seed of the texture, jitter and noise; the same seed gives the same frames.
    size : (W, H), optional
        Output size; defaults to ``scene.size``. Coordinates are scaled to it.
    style : RenderStyle, optional
        Defaults to :func:`default_style`.
    """
    out_w, out_h = scene.size if size is None else (int(size[0]), int(size[1]))
    if out_w < 8 or out_h < 8:
        raise ValueError(f"size must be at least 8×8 px, got {(out_w, out_h)}")
    style = default_style(scene) if style is None else style
    rng = np.random.default_rng(seed)
    jit = float(style.jitter)
    m = int(np.ceil(jit)) + 1 if jit > 0 else 0  # margin for the shift and interpolation
    bg = draw_background(scene, style, (out_w, out_h), m, rng)
    scale = np.array([out_w / scene.size[0], out_h / scene.size[1]])
    n_frames = scene.n_frames
    shifts = rng.uniform(-jit, jit, (n_frames, 2)) if m else np.zeros((n_frames, 2))
    # Shifts on a 1/4 px grid, so each distinct shifted background is interpolated once and
    # cached (a bilinear warp per frame would cost more than the rest of the frame).
    q = 0.25
    shifts = q * np.round(shifts / q)
    cache: dict[tuple[float, float], Frame] = {}
    keep = out_w * out_h * 3 * (2 * np.ceil(jit / q) + 1) ** 2 <= 128e6
    pad = 16
    if style.noise_sigma > 0:
        pos, neg = _noise_bank(rng, (out_w, out_h), style.noise_sigma, pad, n_frames)
        pick = rng.integers(0, len(pos), n_frames)
        offs = rng.integers(0, pad + 1, (n_frames, 2))
    codes = np.array([KIND_CODE[k] for k in scene.kind], np.int64)
    occ_boxes = []
    for occ in scene.meta.get("occluders", []):
        lo = (np.asarray(occ["xy"], float) - np.asarray(occ["wh"], float) / 2) * scale
        hi = (np.asarray(occ["xy"], float) + np.asarray(occ["wh"], float) / 2) * scale
        bottom = hi[1:] if occ.get("depth", True) else np.array([np.inf])
        occ_boxes.append((np.floor(lo).astype(int) - 1, np.ceil(hi).astype(int) + 1,
                          occ.get("hides") == "lower half", bottom))
    for f in range(n_frames):
        dx, dy = float(shifts[f, 0]), float(shifts[f, 1])
        if m:
            crop = cache.get((dx, dy))  # type: ignore[assignment]
            if crop is None:
                warp = np.array([[1.0, 0.0, m + dx], [0.0, 1.0, m + dy]])
                crop = cv2.warpAffine(bg, warp, (out_w, out_h),
                                      flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
                if keep:
                    cache[dx, dy] = crop
        else:
            crop = bg
        img = crop.copy()
        rows = scene.rows(f)
        if rows.stop > rows.start:
            ids = scene.id[rows] - 1
            xy = scene.xy[rows] * scale - np.array([dx, dy])
            wh = scene.wh[rows] * scale
            hd = scene.heading[rows]
            code = codes[ids]
            for kind in np.unique(code):  # at most a few kinds per scene
                sel = code == kind
                oid = ids[sel]
                if kind == 0 or kind == 4:
                    draw_block(img, xy[sel], wh[sel], scene.color[oid])
                elif kind == 1:
                    lw = scene.body[oid] * scale[0]
                    draw_vehicle(img, xy[sel], hd[sel], lw, scene.color[oid], scene.color2[oid])
                elif kind == 2:
                    draw_person(img, xy[sel], wh[sel], scene.color[oid], scene.color2[oid])
                else:
                    draw_point(img, xy[sel], wh[sel], scene.color[oid])
            for lo, hi, lower, bottom_px in occ_boxes:  # occluders in front (X8's car)
                x0, y0 = max(lo[0] - round(dx), 0), max(lo[1] - round(dy), 0)
                x1, y1 = min(hi[0] - round(dx), out_w), min(hi[1] - round(dy), out_h)
                if x1 <= x0 or y1 <= y0:
                    continue
                if not lower:
                    img[y0:y1, x0:x1] = crop[y0:y1, x0:x1]
                    continue
                # the car covers only the lower half of each object behind it (feet above the
                # car's lower edge); an object whose feet are below that edge is in front of
                # it. Inside its box the car shows except where such an upper half, or an
                # object in front, is.
                car = np.ones((y1 - y0, x1 - x0), bool)
                b_lo = np.floor(xy - wh / 2).astype(int) - 1
                b_hi = np.ceil(xy + wh / 2).astype(int) + 1
                behind = xy[:, 1] + wh[:, 1] / 2 <= bottom_px[0] - dy
                top = np.where(behind, np.round(xy[:, 1]).astype(int), b_hi[:, 1])
                ux0, ux1 = np.maximum(b_lo[:, 0], x0), np.minimum(b_hi[:, 0], x1)
                uy0, uy1 = np.maximum(b_lo[:, 1], y0), np.minimum(top, y1)
                for k in np.flatnonzero((ux1 > ux0) & (uy1 > uy0)):  # the few at the car
                    car[uy0[k] - y0 : uy1[k] - y0, ux0[k] - x0 : ux1[k] - x0] = False
                view = img[y0:y1, x0:x1]
                view[car] = crop[y0:y1, x0:x1][car]
        if style.noise_sigma > 0:
            k, ox, oy = int(pick[f]), int(offs[f, 0]), int(offs[f, 1])
            cv2.add(img, pos[k][oy : oy + out_h, ox : ox + out_w], dst=img)
            cv2.subtract(img, neg[k][oy : oy + out_h, ox : ox + out_w], dst=img)
        yield img


def write_video(
    scene: Scene,
    path: str | os.PathLike[str],
    seed: int | np.random.Generator = 0,
    size: tuple[int, int] | None = None,
    style: RenderStyle | None = None,
    progress: bool | None = None,
) -> Path:
    """Render the scene to an MP4 file (OpenCV ``mp4v``), atomically.

    The video is written to a temporary ``.mp4`` beside ``path`` and renamed on success; an
    error or Ctrl-C leaves no partial file. A progress bar is shown on a terminal.
    """
    path = Path(path)
    out_w, out_h = scene.size if size is None else (int(size[0]), int(size[1]))
    if progress is None:
        progress = sys.stderr.isatty()
    with atomic_path(path, suffix=".mp4") as tmp:
        writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), float(scene.fps),
                                 (out_w, out_h))
        if not writer.isOpened():
            raise OSError(f"{path}: OpenCV cannot write MP4 (mp4v) video here")
        try:
            frames = render_frames(scene, seed, (out_w, out_h), style)
            if progress:
                from tqdm import tqdm

                frames = tqdm(frames, total=scene.n_frames, desc=f"render {scene.name}",
                              unit="frame", file=sys.stderr)
            for img in frames:
                writer.write(img)
        finally:
            writer.release()
    return path
