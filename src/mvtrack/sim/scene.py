"""The ground truth of a simulated scene, and how a builder assembles it.

A :class:`Scene` is a struct of arrays over all ``K`` (frame, object) rows, sorted by frame then
id, plus per-object metadata (``N`` objects with ids ``1..N``). A builder computes dense
``(F, N, 2)`` centres and headings and hands them to :func:`assemble`, which derives the boxes,
the visible fractions and the rows.

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


def assemble(
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
