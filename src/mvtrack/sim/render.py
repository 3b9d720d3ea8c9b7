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
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.io.atomic import atomic_path
from mvtrack.sim.intersection import X5_CENTRE, X5_LANE, X5_ROAD_HALF, X5_STOP
from mvtrack.sim.scene import Scene

Frame = NDArray[np.uint8]
_SHIFT = 4  # OpenCV fixed-point bits: sub-pixel vertices at 1/16 px
_ONE = 1 << _SHIFT
_KIND_CODE = {"block": 0, "vehicle": 1, "motorcycle": 1, "person": 2, "point": 3, "box": 4}


@dataclass(frozen=True)
class RenderStyle:
    """How a scene looks.

    Attributes
    ----------
    background : {"flat", "intersection", "plaza", "asphalt"}
        Background layout.
    ground : (int, int, int)
        Base BGR colour of the background (the road for ``flat`` and ``asphalt``).
    texture : float
        Amplitude (grey levels) of the background texture; 0 for a flat colour.
    noise_sigma : float
        Standard deviation of the per-frame sensor noise, grey levels (0: none).
    jitter : float
        Camera jitter: each frame's picture is translated by an independent uniform shift in
        ``[-jitter, jitter]`` px per axis (bilinear, sub-pixel: a shaking camera does not move
        in whole pixels).
    """

    background: str = "asphalt"
    ground: tuple[int, int, int] = (88, 88, 88)
    texture: float = 6.0
    noise_sigma: float = 2.0
    jitter: float = 0.0

    def __post_init__(self) -> None:
        if self.background not in ("flat", "intersection", "plaza", "asphalt"):
            raise ValueError(f"unknown background {self.background!r}")
        if self.noise_sigma < 0 or self.texture < 0 or self.jitter < 0:
            raise ValueError("noise_sigma, texture and jitter must be >= 0")


def default_style(scene: Scene) -> RenderStyle:
    """The style of each scene: X4 exactly as SPEC X4 (flat grey, no noise); X5 with σ = 3
    noise and ±1 px jitter (SPEC X5); X8 on paving with σ = 2; others asphalt."""
    if scene.name == "x4":
        grey = tuple(int(c) for c in scene.meta.get("background", (96, 96, 96)))
        return RenderStyle("flat", grey, 0.0, 0.0, 0.0)  # type: ignore[arg-type]
    if scene.name == "x5":
        return RenderStyle("intersection", (88, 88, 88), 6.0, 3.0, 1.0)
    if scene.name == "x8":
        return RenderStyle("plaza", (112, 118, 122), 5.0, 2.0, 0)
    if scene.name == "crowd":
        return RenderStyle("asphalt", (88, 88, 88), 6.0, 0.0, 0)
    return RenderStyle()


# ---------------------------------------------------------------------- background
def _texture(rng: np.random.Generator, h: int, w: int, amp: float) -> NDArray[np.float32]:
    """Grey-level texture: smooth blotches plus fine grain, amplitude ``amp``."""
    if amp <= 0:
        return np.zeros((h, w), np.float32)
    coarse = rng.standard_normal((h // 12 + 2, w // 12 + 2)).astype(np.float32)
    blotch = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_CUBIC)
    grain = rng.standard_normal((h, w)).astype(np.float32)
    return amp * (0.8 * blotch + 0.5 * grain)


def _poly(img: Frame, pts: NDArray[np.float64], color: tuple[int, ...]) -> None:
    cv2.fillConvexPoly(img, np.round(pts * _ONE).astype(np.int32), color, cv2.LINE_8, _SHIFT)


def _fill(base: tuple[int, int, int], tex: NDArray[np.float32]) -> Frame:
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
        _poly(mask, p, (255,))
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
            _poly(img, quad(np.array([[x, -0.8], [x - 7, -0.8], [x - 7, 0.8], [x, 0.8]]), rm),
                  line)
        s = -X5_STOP + 3.0  # stop line across the incoming lane, just ahead of waiting cars
        _poly(img, quad(np.array([[s, 0.5], [s + 2, 0.5], [s + 2, 2 * X5_LANE - 0.5],
                                  [s, 2 * X5_LANE - 0.5]]), rm), line)
    for pole in scene.meta.get("poles", []):
        p = to_px(np.array([pole], float))[0]
        base = np.round(p * _ONE).astype(np.int32)
        shadow = np.round((p + np.array([5.0, 3.0]) * scale) * _ONE).astype(np.int32)
        cv2.line(img, tuple(base), tuple(shadow), (40, 50, 45), max(1, round(2 * scale)),
                 cv2.LINE_AA, _SHIFT)
        cv2.circle(img, tuple(base), int(3.2 * scale * _ONE), (215, 245, 250), -1,
                   cv2.LINE_AA, _SHIFT)


def _background(scene: Scene, style: RenderStyle, size: tuple[int, int], margin: int,
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
        _draw_vehicle(img, to_px(np.array([occ["xy"]], float)), np.zeros(1),
                      np.array([occ["wh"]], float) * np.array([sx, sy]),
                      np.array([occ["color"]], np.uint8),
                      np.array([occ.get("color2", (70, 60, 55))], np.uint8))
    return img


# ---------------------------------------------------------------------- objects
def _corners(xy: NDArray[np.float64], hd: NDArray[np.float64],
             x0: float, x1: float, y0: float, y1: float,
             lw: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 4, 2) corners of the local rectangles ``[x0, x1]·L × [y0, y1]·W`` of n bodies."""
    c, s = np.cos(hd)[:, None], np.sin(hd)[:, None]
    lx = np.array([x0, x1, x1, x0])[None] * lw[:, :1]
    ly = np.array([y0, y0, y1, y1])[None] * lw[:, 1:]
    return np.stack([xy[:, :1] + c * lx - s * ly, xy[:, 1:] + s * lx + c * ly], axis=-1)


def _draw_vehicle(img: Frame, xy: NDArray[np.float64], hd: NDArray[np.float64],
                  lw: NDArray[np.float64], col: NDArray[np.uint8],
                  col2: NDArray[np.uint8]) -> None:
    """Two-tone bodies: body, a shaded right side, and a cabin (windows) of the second tone."""
    inner = np.maximum(lw - 1.0, 1.0)  # pixel centres: a body L px long covers L pixels
    polys = np.stack([
        _corners(xy, hd, -0.5, 0.5, -0.5, 0.5, inner),  # body
        _corners(xy, hd, -0.5, 0.5, 0.3, 0.5, inner),  # shaded right side
        _corners(xy, hd, -0.3, 0.15, -0.32, 0.32, inner),  # cabin
    ], axis=1)
    ipolys = np.round(polys * _ONE).astype(np.int32)
    tones = np.stack([col, (col.astype(np.float64) * 0.85).astype(np.uint8), col2], 1).tolist()
    for i in range(xy.shape[0]):  # the few vehicles of one frame
        for j in range(3):
            cv2.fillConvexPoly(img, ipolys[i, j], tones[i][j], cv2.LINE_8, _SHIFT)


def _draw_block(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
                col: NDArray[np.uint8]) -> None:
    """Plain axis-aligned rectangles (X4's vehicles, crowd targets)."""
    pts = _corners(xy, np.zeros(xy.shape[0]), -0.5, 0.5, -0.5, 0.5, np.maximum(wh - 1.0, 1.0))
    ipts = np.round(pts * _ONE).astype(np.int32)
    for i in range(xy.shape[0]):
        cv2.fillConvexPoly(img, ipts[i], tuple(int(v) for v in col[i]), cv2.LINE_8, _SHIFT)


_SKIN = (120, 160, 205)


def _draw_person(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
                 col: NDArray[np.uint8], col2: NDArray[np.uint8]) -> None:
    """A small blob: head, torso (main tone) and legs (second tone) inside the box."""
    w, h = wh[:, 0], wh[:, 1]
    head_r = np.maximum(0.3 * w, 1.0)
    head = np.stack([xy[:, 0], xy[:, 1] - h / 2 + head_r + 0.5], -1)
    torso = np.stack([xy[:, 0], xy[:, 1] - 0.06 * h], -1)
    axes = np.stack([np.maximum(w / 2 - 0.5, 1.0), 0.28 * h], -1)
    legs = _corners(np.stack([xy[:, 0], xy[:, 1] + 0.3 * h], -1), np.zeros(xy.shape[0]),
                    -0.5, 0.5, -0.5, 0.5, np.stack([0.75 * w, 0.4 * h - 1.0], -1))
    to_i = lambda a: np.round(a * _ONE).astype(np.int32)  # noqa: E731
    head_i, torso_i, axes_i, legs_i = to_i(head), to_i(torso), to_i(axes), to_i(legs)
    r_i = to_i(head_r)
    for i in range(xy.shape[0]):
        cv2.fillConvexPoly(img, legs_i[i], tuple(int(v) for v in col2[i]), cv2.LINE_8, _SHIFT)
        cv2.ellipse(img, tuple(torso_i[i]), tuple(axes_i[i]), 0.0, 0.0, 360.0,
                    tuple(int(v) for v in col[i]), -1, cv2.LINE_8, _SHIFT)
        cv2.circle(img, tuple(head_i[i]), int(r_i[i]), _SKIN, -1, cv2.LINE_8, _SHIFT)


def _draw_point(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
                col: NDArray[np.uint8]) -> None:
    r = np.round(np.maximum(wh.min(axis=1) / 2, 1.0) * _ONE).astype(np.int32)
    c = np.round(xy * _ONE).astype(np.int32)
    for i in range(xy.shape[0]):
        cv2.circle(img, tuple(c[i]), int(r[i]), tuple(int(v) for v in col[i]), -1,
                   cv2.LINE_8, _SHIFT)


# ---------------------------------------------------------------------- frames
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
    bg = _background(scene, style, (out_w, out_h), m, rng)
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
    codes = np.array([_KIND_CODE[k] for k in scene.kind], np.int64)
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
                    _draw_block(img, xy[sel], wh[sel], scene.color[oid])
                elif kind == 1:
                    lw = scene.body[oid] * scale[0]
                    _draw_vehicle(img, xy[sel], hd[sel], lw, scene.color[oid], scene.color2[oid])
                elif kind == 2:
                    _draw_person(img, xy[sel], wh[sel], scene.color[oid], scene.color2[oid])
                else:
                    _draw_point(img, xy[sel], wh[sel], scene.color[oid])
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
    bg = _background(scene, empty, (out_w, out_h), m, np.random.default_rng(seed))
    return bg[m : m + out_h, m : m + out_w].copy()


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
