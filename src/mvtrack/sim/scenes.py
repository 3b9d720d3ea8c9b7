"""Simulated scenes with ground truth held as arrays (SPEC §5 X4, X5, X7, X8; issue 3 "crowd").

A :class:`Scene` is a struct of arrays over all ``K`` (frame, object) rows, sorted by frame then
id, plus per-object metadata (``N`` objects with ids ``1..N``). Builders:

* :func:`x4_nine_vehicles` — paper 1's synthetic 9 vehicles (SPEC X4), exact formulas.
* :func:`x5_intersection` — the reconstructed 4-way intersection (SPEC X5).
* :func:`x7_crossing` — paper 2's two crossing point targets (SPEC X7).
* :func:`x8_splitting_group` — paper 2's group of three splitting behind a car (SPEC X8).
* :func:`crowd` — ``N`` constant-velocity targets for scale tests (issue 3).

Conventions: frames are 0-based in memory (``gt_mot`` writes them 1-based, as MOTChallenge
files are); pixel centres sit at integer coordinates; ``xy`` is the box centre, ``wh`` the
axis-aligned box (for rotating vehicles, the box around the rotated body).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Rows whose visible fraction (inside the image, not behind an occluder) is at least this
#: are ``visible``: detected by :func:`mvtrack.sim.detections.detections_from_scene` and
#: written to ``gt.txt``.
VISIBLE_MIN = 0.5

#: MOTChallenge (MOT17) class numbers written in the 8th column of ``gt.txt``.
MOT_CLASS = {"person": 1, "vehicle": 3, "block": 3, "motorcycle": 5, "point": 1, "box": 1}

#: Scene names accepted by :func:`build`.
SCENES = ("x4", "x5", "x7", "x8", "crowd")


@dataclass(frozen=True, eq=False)
class Scene:
    """Ground truth of a simulated scene as a struct of arrays.

    Attributes
    ----------
    name : str
        Scene name (``"x4"``, ``"x5"``, ``"x7"``, ``"x8"``, ``"crowd"``).
    fps : float
        Frame rate.
    size : (int, int)
        Image size ``(W, H)`` in pixels.
    n_frames : int
        Number of frames ``0 .. n_frames-1``.
    frame, id : (K,) int64
        Frame index and object id (``1..N``) of each row; sorted by frame, then id.
    xy, wh : (K, 2) float64
        Box centre and axis-aligned box size.
    heading : (K,) float64
        Direction of travel in radians (image axes: 0 = +x, π/2 = +y).
    visibility : (K,) float64
        Fraction of the box inside the image and not behind an occluder.
    category, kind : (N,) str
        Per object (index ``id - 1``): the scene's category (e.g. ``"left"`` in X5) and the
        drawing kind (``"vehicle"``, ``"block"``, ``"person"``, ``"motorcycle"``, ``"point"``,
        ``"box"``).
    body : (N, 2) float64
        Body length along the heading and width across it (vehicles), or the box ``(w, h)``.
    rotates : (N,) bool
        Whether the body turns with the heading (the box then changes with it).
    color, color2 : (N, 3) uint8
        Main and second tone, BGR.
    meta : dict
        Scene-specific layout used by the renderer (roads, poles, occluders, ...).
    """

    name: str
    fps: float
    size: tuple[int, int]
    n_frames: int
    frame: IntArray
    id: IntArray
    xy: FloatArray
    wh: FloatArray
    heading: FloatArray
    visibility: FloatArray
    category: NDArray[np.str_]
    kind: NDArray[np.str_]
    body: FloatArray
    rotates: NDArray[np.bool_]
    color: NDArray[np.uint8]
    color2: NDArray[np.uint8]
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        k = self.frame.shape[0]
        for name in ("id", "heading", "visibility"):
            if getattr(self, name).shape != (k,):
                raise ValueError(f"Scene: {name} must have shape ({k},)")
        for name in ("xy", "wh"):
            if getattr(self, name).shape != (k, 2):
                raise ValueError(f"Scene: {name} must have shape ({k}, 2)")
        if k and np.any(np.diff(self.frame) < 0):
            raise ValueError("Scene: rows must be sorted by frame")
        starts = np.searchsorted(self.frame, np.arange(self.n_frames + 1))
        object.__setattr__(self, "_starts", starts)

    # ------------------------------------------------------------------ access
    @property
    def n_objects(self) -> int:
        """Number of objects ``N`` (ids ``1..N``)."""
        return int(self.category.shape[0])

    @property
    def visible(self) -> NDArray[np.bool_]:
        """(K,) rows with ``visibility >= VISIBLE_MIN``."""
        return self.visibility >= VISIBLE_MIN

    def rows(self, frame: int) -> slice:
        """Slice of the rows of ``frame`` (empty outside ``0..n_frames-1``)."""
        if not 0 <= frame < self.n_frames:
            return slice(0, 0)
        s = self._starts  # type: ignore[attr-defined]
        return slice(int(s[frame]), int(s[frame + 1]))

    def trajectory(self, obj_id: int) -> tuple[IntArray, FloatArray]:
        """Frames and centres of one object (all its rows, visible or not)."""
        sel = self.id == obj_id
        return self.frame[sel], self.xy[sel]

    def ids_of(self, category: str) -> IntArray:
        """Ids of the objects of a category."""
        return np.flatnonzero(self.category == category).astype(np.int64) + 1

    def truncate(self, n_frames: int) -> Scene:
        """The first ``n_frames`` frames of the scene."""
        if not 1 <= n_frames <= self.n_frames:
            raise ValueError(
                f"frames must be in 1..{self.n_frames} for scene {self.name}, got {n_frames}"
            )
        end = self.rows(n_frames - 1).stop
        return Scene(
            self.name, self.fps, self.size, n_frames, self.frame[:end], self.id[:end],
            self.xy[:end], self.wh[:end], self.heading[:end], self.visibility[:end],
            self.category, self.kind, self.body, self.rotates, self.color, self.color2,
            self.meta,
        )

    def gt_mot(self, include_hidden: bool = False) -> FloatArray:
        """MOTChallenge ground-truth rows (MOT17 layout), shape (K', 9).

        Columns: frame (1-based), id, bb_left, bb_top, bb_width, bb_height, consider flag
        (1 visible / 0 hidden), class (:data:`MOT_CLASS`), visibility ratio.

        Parameters
        ----------
        include_hidden : bool
            Also write rows below :data:`VISIBLE_MIN` (with consider flag 0). By default only
            visible rows are written, so evaluators that ignore the flag stay correct.
        """
        vis = self.visible
        sel = slice(None) if include_hidden else vis
        cls = np.array([MOT_CLASS[k] for k in self.kind], dtype=np.float64)
        ids = self.id[sel]
        out = np.empty((ids.shape[0], 9))
        out[:, 0] = self.frame[sel] + 1
        out[:, 1] = ids
        out[:, 2:4] = self.xy[sel] - self.wh[sel] / 2
        out[:, 4:6] = self.wh[sel]
        out[:, 6] = vis[sel]
        out[:, 7] = cls[ids - 1]
        out[:, 8] = self.visibility[sel]
        return out


# ---------------------------------------------------------------------- assembly helpers
def _box_wh(body: FloatArray, heading: FloatArray, rotates: NDArray[np.bool_]) -> FloatArray:
    """Axis-aligned box of a body ``(L, W)`` turned to ``heading`` (broadcast over rows)."""
    length, width = body[..., 0], body[..., 1]
    if not np.any(rotates):
        return np.broadcast_to(body, (*np.shape(heading), 2)).copy()
    c, s = np.abs(np.cos(heading)), np.abs(np.sin(heading))
    w = np.where(rotates, length * c + width * s, length)
    h = np.where(rotates, length * s + width * c, width)
    return np.stack([w, h], axis=-1)


def _visibility(
    xy: FloatArray, wh: FloatArray, size: tuple[int, int], occluders: list[dict[str, Any]]
) -> tuple[FloatArray, FloatArray]:
    """Fraction of each box inside the image, and that fraction minus occluded parts.

    An occluder hides the part of a box inside its rectangle; one with ``hides == "lower
    half"`` (a parked car that people walk behind: it covers their legs, not their heads)
    hides only the part of the box's lower half inside it, and only of boxes behind it (their
    lower edge above the occluder's); a box whose lower edge is below it is in front. With
    ``depth`` False every box counts as behind it.
    """
    lo, hi = xy - wh / 2, xy + wh / 2
    area = np.maximum(wh.prod(axis=-1), 1e-12)
    img = np.array(size, dtype=np.float64)
    inside = np.clip(np.minimum(hi, img) - np.maximum(lo, 0.0), 0.0, None).prod(axis=-1)
    inside_frac = inside / area
    hidden = np.zeros_like(inside)
    for occ in occluders:  # a handful of static occluders per scene, not per target
        o_lo = np.asarray(occ["xy"], float) - np.asarray(occ["wh"], float) / 2
        o_hi = o_lo + np.asarray(occ["wh"], float)
        top = lo.copy()
        if occ.get("hides") == "lower half":  # the lower half of a box behind the occluder
            behind = hi[..., 1] <= o_hi[1] if occ.get("depth", True) else True
            top[..., 1] = np.where(behind, xy[..., 1], hi[..., 1])
        a = np.maximum(top, np.maximum(o_lo, 0.0))
        b = np.minimum(hi, np.minimum(o_hi, img))
        hidden += np.clip(b - a, 0.0, None).prod(axis=-1)
    return np.minimum(inside_frac, 1.0), np.clip((inside - hidden) / area, 0.0, 1.0)


def _assemble(
    name: str,
    fps: float,
    size: tuple[int, int],
    xy: FloatArray,
    heading: FloatArray,
    *,
    category: list[str] | NDArray[np.str_],
    kind: list[str] | NDArray[np.str_],
    body: FloatArray,
    rotates: NDArray[np.bool_],
    color: NDArray[np.uint8],
    color2: NDArray[np.uint8] | None = None,
    meta: dict[str, Any] | None = None,
) -> Scene:
    """Build a :class:`Scene` from dense ``(F, N, 2)`` centres (NaN where absent)."""
    meta = dict(meta or {})
    n_frames, n = xy.shape[:2]
    body = np.asarray(body, np.float64).reshape(n, 2)
    rotates = np.broadcast_to(np.asarray(rotates, bool), (n,)).copy()
    wh = _box_wh(body[None], heading, rotates[None])
    present = np.all(np.isfinite(xy), axis=-1)
    xy0 = np.where(present[..., None], xy, 0.0)
    inside, vis = _visibility(xy0, wh, size, meta.get("occluders", []))
    keep = present & (inside > 0)  # rows whose box touches the image
    f_idx, o_idx = np.nonzero(keep)  # row-major: sorted by frame, then id
    color = np.asarray(color, np.uint8).reshape(n, 3)
    if color2 is None:
        color2 = _second_tone(color)
    return Scene(
        name=name, fps=float(fps), size=(int(size[0]), int(size[1])), n_frames=n_frames,
        frame=f_idx.astype(np.int64), id=o_idx.astype(np.int64) + 1,
        xy=xy0[keep], wh=wh[keep], heading=np.asarray(heading, float)[keep],
        visibility=vis[keep], category=np.asarray(category, dtype=str),
        kind=np.asarray(kind, dtype=str), body=body, rotates=rotates,
        color=color, color2=np.asarray(color2, np.uint8).reshape(n, 3), meta=meta,
    )


def luminance(bgr: NDArray[Any]) -> FloatArray:
    """ITU-R BT.601 luma of BGR colours, ``Y = 0.299 R + 0.587 G + 0.114 B``."""
    bgr = np.asarray(bgr, np.float64)
    return 0.114 * bgr[..., 0] + 0.587 * bgr[..., 1] + 0.299 * bgr[..., 2]


def _second_tone(color: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """Window/cabin tone: dark glass on light bodies, light glass on dark ones.

    Both stay ≥ 40 grey levels of luma away from the roads (luma ≈ 88–110), so a vehicle is
    one blob to background subtraction rather than a ring around its cabin.
    """
    light = luminance(color) > 100
    dark_glass = np.array([60, 45, 40], np.uint8)
    light_glass = np.array([170, 160, 150], np.uint8)
    return np.where(light[:, None], dark_glass, light_glass).astype(np.uint8)


# ---------------------------------------------------------------------- paths
@dataclass(frozen=True)
class Path2D:
    """A planar path of straight lines and circular arcs, walked by arc length.

    Segments are ``("line", p0, p1)`` or ``("arc", centre, r, a0, sweep)`` with the point
    ``centre + r (cos a, sin a)``, ``a = a0 + sweep·u`` for ``u ∈ [0, 1]``. Beyond either end
    the path continues straight along its end heading.
    """

    segments: tuple[tuple[Any, ...], ...]

    @property
    def lengths(self) -> FloatArray:
        """Length of each segment."""
        out = []
        for seg in self.segments:
            if seg[0] == "line":
                out.append(float(np.hypot(*np.subtract(seg[2], seg[1]))))
            else:
                out.append(abs(seg[2] * seg[4]))
        return np.array(out)

    @property
    def length(self) -> float:
        """Total length."""
        return float(self.lengths.sum())

    def at(self, s: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Positions ``(..., 2)`` and headings at arc lengths ``s`` (vectorised)."""
        s = np.asarray(s, dtype=np.float64)
        lengths = self.lengths
        starts = np.concatenate([[0.0], np.cumsum(lengths)])
        seg = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(lengths) - 1)
        xy = np.zeros((*s.shape, 2))
        hd = np.zeros(s.shape)
        for i, sg in enumerate(self.segments):  # a few segments, vectorised over s
            m = seg == i
            if not m.any():
                continue
            d = s[m] - starts[i]  # may be < 0 before the first or > L after the last
            if sg[0] == "line":
                p0, p1 = np.asarray(sg[1], float), np.asarray(sg[2], float)
                u = (p1 - p0) / max(lengths[i], 1e-12)
                xy[m] = p0 + d[:, None] * u
                hd[m] = np.arctan2(u[1], u[0])
            else:
                c, r, a0, sweep = np.asarray(sg[1], float), sg[2], sg[3], sg[4]
                sign = np.sign(sweep)
                dc = np.clip(d, 0.0, lengths[i])
                a = a0 + sign * dc / r
                h = a + sign * np.pi / 2
                extra = d - dc  # straight continuation past either end of an arc
                xy[m] = c + r * np.stack([np.cos(a), np.sin(a)], -1) + extra[:, None] * np.stack(
                    [np.cos(h), np.sin(h)], -1
                )
                hd[m] = h
        return xy, np.arctan2(np.sin(hd), np.cos(hd))


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
    return _assemble(
        "x4", 30, (320, 240), xy, hd,
        category=["side-by-side"] * 5 + ["crossing"] * 2 + ["constant", "fast"],
        kind=["block"] * 9, body=np.tile([12.0, 8.0], (9, 1)), rotates=np.zeros(9, bool),
        color=X4_COLORS, color2=X4_COLORS, meta={"background": (96, 96, 96)},
    )


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
    return _assemble(
        "x7", 30, (320, 240), xy, hd, category=["T1", "T2"], kind=["point", "point"],
        body=np.full((2, 2), 4.0), rotates=np.zeros(2, bool),
        color=np.array([[255, 255, 255], [0, 255, 255]], np.uint8),
        meta={"jitter": float(jitter)},
    )


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
    return _assemble(
        "crowd", fps, size, xy, hd, category=["target"] * n, kind=["box"] * n, body=wh,
        rotates=np.zeros(n, bool), color=color,
    )


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


def _rot(theta: float) -> FloatArray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


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
    rot, c = _rot(theta), np.array(X5_CENTRE)
    out: list[tuple[Any, ...]] = []
    for sg in segs:
        if sg[0] == "line":
            out.append(("line", tuple(c + rot @ sg[1]), tuple(c + rot @ sg[2])))
        else:
            out.append(("arc", tuple(c + rot @ np.asarray(sg[1])), sg[2], sg[3] + theta, sg[4]))
    return Path2D(tuple(out))


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


def _place(
    path: Path2D, s: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Centres (NaN off the path) and headings for arc lengths ``s``."""
    xy, hd = path.at(s)
    off = (s < 0) | (s > path.length)
    xy[off] = np.nan
    return xy, hd


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
                t0 = float(rng.uniform(0.0, 300.0))
                s = v * (t - t0)
            p, h = _place(path, s)
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
    in 1.5–3 px/frame; entries (path starts, 20 px off the image) uniform over frames 0–300.
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
    return _assemble(
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


# ---------------------------------------------------------------------- X8
def x8_splitting_group(seed: int | np.random.Generator = 0, car_depth: bool = True) -> Scene:
    """Paper 2's group of three people splitting behind a car, plus 11 others (SPEC X8).

    320×240, 15 fps, 240 frames. A static white car 44×22 px centred at (96, 64) is an
    occluder (``meta["occluders"]``) in front of the people that hides at most the lower half
    of each (``hides = "lower half"``: people walk behind a parked car, which covers their legs
    and not their heads, SPEC X8 as revised), so the group stays visible while it splits. P1–P3
    (ids 1–3, category ``group``) start at (18, 12) with v = (1.2, 0.8), side by side ±9 px
    across the direction of motion (P1 on the upper-right side), 8×16 px, so their blobs
    merge. With ``car_depth`` False the car hides the lower half of everyone over it, also of
    people whose feet are already below its lower edge (a variant of the [R] geometry). At
    frame 60 (split point (90, 60), over the car) they change velocity: P1
    (1.44, 0.46), P2 (0.25, 1.4), P3 (−0.15, 1.4). Their colours differ from the paving by
    ≥ 40 grey levels of luma, so each person's visible upper half is one blob. Eleven others
    on straight lines, kept ≥ 30 px (centre distance) from every group member, ≥ 24 px from
    one another and clear of the car: 6 ``car`` (28×12 px, 3–5 px/frame), 2 ``motorcycle``
    (12×8 px, 4–6), 3 ``pedestrian`` (8×16 px, 1–1.5).
    """
    rng = np.random.default_rng(seed)
    n_frames, size = 240, (320, 240)
    t = np.arange(n_frames, dtype=np.float64)
    v0 = np.array([1.2, 0.8])
    d = v0 / np.linalg.norm(v0)
    across = np.array([d[1], -d[0]])  # right-and-up across the direction of motion
    start = np.array([18.0, 12.0]) + np.outer([9.0, 0.0, -9.0], across)  # P1, P2, P3
    v1 = np.array([[1.44, 0.46], [0.25, 1.4], [-0.15, 1.4]])
    tt = t[:, None, None]
    at60 = start + 60.0 * v0
    group = np.where(tt < 60, start + tt * v0, at60 + (tt - 60.0) * v1)  # (F, 3, 2)
    group_hd = np.where(t[:, None] < 60, np.arctan2(v0[1], v0[0]), np.arctan2(v1[:, 1], v1[:, 0]))
    # a light cabin: the people's upper halves (luma 64–73, skin 169) stand out against every
    # part of the car they pass in front of
    occ = {"xy": (96.0, 64.0), "wh": (44.0, 22.0), "color": (245, 245, 245),
           "color2": (205, 205, 200), "hides": "lower half", "depth": bool(car_depth)}
    occ_lo = np.array(occ["xy"]) - np.array(occ["wh"]) / 2 - 4.0
    occ_hi = np.array(occ["xy"]) + np.array(occ["wh"]) / 2 + 4.0

    others = [("car", 28.0, 12.0, 3.0, 5.0)] * 6 + [("motorcycle", 12.0, 8.0, 4.0, 6.0)] * 2
    others += [("pedestrian", 8.0, 16.0, 1.0, 1.5)] * 3
    n = 3 + len(others)
    xy = np.full((n_frames, n, 2), np.nan)
    hd = np.zeros((n_frames, n))
    xy[:, :3], hd[:, :3] = group, group_hd
    body = np.zeros((n, 2))
    body[:3] = (8.0, 16.0)
    img = np.array(size, float)
    for j, (cat, length, width, vlo, vhi) in enumerate(others):
        i = 3 + j
        body[i] = (length, width)
        half = max(length, width) / 2
        for _attempt in range(5000):
            spd = rng.uniform(vlo, vhi)
            if cat == "pedestrian":  # enter at a random edge point, heading inwards ±60°
                edge = int(rng.integers(4))
                inward = [0.0, np.pi / 2, np.pi, -np.pi / 2][edge]
                ang = inward + rng.uniform(-np.pi / 3, np.pi / 3)
            else:  # vehicles drive along the image axes
                edge = int(rng.integers(4))
                ang = [0.0, np.pi / 2, np.pi, -np.pi / 2][edge]
            u = np.array([np.cos(ang), np.sin(ang)])
            lateral = rng.uniform(20.0, img[1 - edge % 2] - 20.0)
            p0 = np.empty(2)
            p0[edge % 2] = -half if edge < 2 else img[edge % 2] + half
            p0[1 - edge % 2] = lateral
            t0 = rng.uniform(0.0, 200.0)
            p = p0 + (t - t0)[:, None] * spd * u
            p[t < t0] = np.nan
            if np.any(np.all((p > occ_lo - half) & (p < occ_hi + half), axis=1)):
                continue  # would pass behind or over the static car
            dg = np.linalg.norm(group - p[:, None], axis=-1)
            if np.any(dg[np.isfinite(dg)] < 30.0):
                continue
            do = np.linalg.norm(xy[:, 3:i] - p[:, None], axis=-1)
            if np.any(do[np.isfinite(do)] < 24.0):
                continue
            xy[:, i], hd[:, i] = p, ang
            break
        else:  # pragma: no cover
            raise RuntimeError(f"x8_splitting_group: could not place target {i + 1} ({cat})")
    kinds = ["person"] * 3 + [
        "vehicle" if c == "car" else "motorcycle" if c == "motorcycle" else "person"
        for c, *_ in others
    ]
    # P1 red, P2 blue, P3 green: luma 65, 64, 73 against the paving's 118
    people_colors = np.array(
        [[20, 20, 170], [200, 60, 20], [20, 110, 20], [20, 20, 20], [220, 220, 60],
         [40, 200, 230], [180, 40, 160], [240, 240, 240], [0, 120, 255]], np.uint8)
    color = np.zeros((n, 3), np.uint8)
    color[:3] = people_colors[:3]
    color[3:] = np.concatenate([X5_COLORS[[3, 4, 6, 1, 9, 2]], X5_COLORS[[3, 8]],
                                people_colors[[3, 4, 5]]])
    return _assemble(
        "x8", 15, size, xy, hd,
        category=["group"] * 3 + [c for c, *_ in others], kind=kinds, body=body,
        rotates=np.array([k in ("vehicle", "motorcycle") for k in kinds]), color=color,
        meta={"occluders": [occ], "group_ids": (1, 2, 3), "split_frame": 60,
              "split_point": (90.0, 60.0)},
    )


# ---------------------------------------------------------------------- registry
def build(name: str, *, seed: int = 0, frames: int | None = None, n: int | None = None) -> Scene:
    """Build a scene by name (``x4``, ``x5``, ``x7``, ``x8``, ``crowd``).

    ``frames`` truncates a fixed-length scene (or sets the crowd's length, default 300);
    ``n`` is the crowd's number of targets (default 100) and is refused for other scenes.
    """
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; choose one of {', '.join(SCENES)}")
    if n is not None and name != "crowd":
        raise ValueError(f"--n applies only to the crowd scene, not {name}")
    if name == "crowd":
        return crowd(100 if n is None else n, frames=300 if frames is None else frames, seed=seed)
    scene = {
        "x4": lambda: x4_nine_vehicles(),
        "x5": lambda: x5_intersection(seed),
        "x7": lambda: x7_crossing(seed),
        "x8": lambda: x8_splitting_group(seed),
    }[name]()
    return scene if frames is None else scene.truncate(frames)
