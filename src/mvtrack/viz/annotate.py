"""Overlay tracks on video frames: boxes, IDs, life-cycle state, trails and gate regions.

Everything here works on whole frames of tracks at once: box outlines, gate outlines and trails
are built as arrays of polygon vertices and handed to one :func:`cv2.polylines` call per
colour; only the ID labels need one :func:`cv2.putText` call each.

The gate of a track is the region ``{z : (z - c)ᵀ C⁻¹ (z - c) ≤ r²}`` around its predicted
position ``c``: a circle of radius ``r`` for the Euclidean gate (eq. 8 of paper 2, circular mask
of paper 1 §1.1) with ``C = I``, an axis-aligned ellipse for the uncoupled gate (eq. 9 of paper 2,
``C = diag(P̄x, P̄y)``), the rotated coupled region (SPEC §2.3) or the Mahalanobis χ² gate
(``C = S = P̄ + R``, the default), as the tracker applies them: the regions come from
:meth:`mvtrack.tracking.Tracker.gates` (:class:`mvtrack.association.gate.GateRegions`).
:func:`gate_ellipses` turns ``(C, r²)`` into semi-axes and an angle.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from collections.abc import Callable, Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.association.gate import GateRegions
from mvtrack.types import TrackFrame, TrackState
from mvtrack.viz.labels import place_frame_labels

FloatArray = NDArray[np.float64]

#: BGR colour of each life-cycle state
STATE_COLORS: dict[int, tuple[int, int, int]] = {
    int(TrackState.TENTATIVE): (160, 160, 160),  # grey
    int(TrackState.CONFIRMED): (60, 200, 60),  # green
    int(TrackState.COASTING): (0, 165, 255),  # orange
    int(TrackState.STOPPED): (255, 80, 40),  # blue
}
#: short label of each state, drawn after the ID
STATE_LABELS: dict[int, str] = {
    int(TrackState.TENTATIVE): "t",
    int(TrackState.CONFIRMED): "",
    int(TrackState.COASTING): "c",
    int(TrackState.STOPPED): "s",
}
#: colour of the gate outlines (BGR, yellow)
GATE_COLOR: tuple[int, int, int] = (0, 230, 255)
#: palette of trail colours, chosen by ``track_id % len(TRAIL_PALETTE)``
TRAIL_PALETTE: NDArray[np.uint8] = np.array(
    [
        [230, 25, 75], [60, 180, 75], [255, 225, 25], [0, 130, 200], [245, 130, 48],
        [145, 30, 180], [70, 240, 240], [240, 50, 230], [210, 245, 60], [250, 190, 212],
        [0, 128, 128], [170, 110, 40],
    ],
    dtype=np.uint8,
)[:, ::-1]  # RGB -> BGR


def gate_ellipses(cov: FloatArray, r2: float | FloatArray) -> tuple[FloatArray, FloatArray]:
    """Semi-axes and orientation of the gate ellipses ``Δᵀ C⁻¹ Δ ≤ r²``.

    For a symmetric positive definite 2×2 matrix ``C = [[a, b], [b, d]]`` the eigenvalues are

    .. math:: \\lambda_{1,2} = \\tfrac{a+d}{2} \\pm \\sqrt{\\left(\\tfrac{a-d}{2}\\right)^2 + b^2}

    and the major axis points at ``θ = ½ atan2(2b, a − d)``; the semi-axes are
    ``sqrt(r² λ)``. Closed form, so the whole batch is a handful of array operations.

    Parameters
    ----------
    cov : (K, 2, 2) float
        Shape matrices ``C`` (``I`` for a circle, ``diag(P̄x, P̄y)`` for eq. (9) of paper 2,
        the coupled covariance of SPEC §2.3, or the innovation covariance ``S``).
    r2 : float or (K,) float
        Squared gate threshold (px² for a circle with ``C = I``; χ² value otherwise).

    Returns
    -------
    axes : (K, 2) float
        Semi-major and semi-minor axis in pixels.
    angle : (K,) float
        Angle of the major axis in degrees, from +x towards +y (image coordinates).
    """
    cov = np.asarray(cov, dtype=np.float64).reshape(-1, 2, 2)
    a, b, d = cov[:, 0, 0], 0.5 * (cov[:, 0, 1] + cov[:, 1, 0]), cov[:, 1, 1]
    mean = 0.5 * (a + d)
    rad = np.sqrt((0.5 * (a - d)) ** 2 + b**2)
    lam = np.stack([mean + rad, np.maximum(mean - rad, 0.0)], axis=1)
    axes = np.sqrt(np.asarray(r2, dtype=np.float64).reshape(-1, 1) * lam)
    angle = np.degrees(0.5 * np.arctan2(2.0 * b, a - d))
    return axes, angle


def ellipse_points(
    center: FloatArray, axes: FloatArray, angle_deg: FloatArray, n_points: int = 36
) -> FloatArray:
    """Points (K, n_points, 2) on ellipses with semi-axes ``axes`` turned by ``angle_deg``."""
    center = np.asarray(center, dtype=np.float64).reshape(-1, 2)
    t = np.linspace(0.0, 2.0 * np.pi, n_points, endpoint=False)
    th = np.radians(np.asarray(angle_deg, dtype=np.float64)).reshape(-1, 1)
    ca, sa = np.cos(th), np.sin(th)
    u = axes[:, :1] * np.cos(t)  # along the major axis, (K, P)
    v = axes[:, 1:] * np.sin(t)
    x = center[:, :1] + ca * u - sa * v
    y = center[:, 1:] + sa * u + ca * v
    return np.stack([x, y], axis=2)


def ellipse_polygons(
    center: FloatArray, axes: FloatArray, angle_deg: FloatArray, n_points: int = 36
) -> NDArray[np.int32]:
    """Vertices (K, n_points, 2) of ellipses in integer pixels, for :func:`cv2.polylines`."""
    return np.rint(ellipse_points(center, axes, angle_deg, n_points)).astype(np.int32)


def box_polygons(xy: FloatArray, wh: FloatArray) -> NDArray[np.int32]:
    """Vertices (K, 4, 2) of axis-aligned boxes centred on ``xy`` with size ``wh``."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    half = np.asarray(wh, dtype=np.float64).reshape(-1, 2) / 2.0
    corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    return np.rint(xy[:, None, :] + corners[None] * half[:, None, :]).astype(np.int32)


def _finite_rows(*arrays: FloatArray) -> NDArray[np.bool_]:
    ok = np.ones(arrays[0].shape[0], dtype=bool)
    for arr in arrays:
        ok &= np.isfinite(arr.reshape(arr.shape[0], int(np.prod(arr.shape[1:])))).all(axis=1)
    return ok


def draw_gates(
    image: NDArray[np.uint8],
    center: FloatArray,
    cov: FloatArray,
    r2: float | FloatArray,
    color: tuple[int, int, int] = GATE_COLOR,
    thickness: int = 1,
) -> NDArray[np.uint8]:
    """Draw the gate regions ``(z − c)ᵀ C⁻¹ (z − c) ≤ r²`` in place; returns ``image``.

    A circle of radius ``g`` is ``cov = I``, ``r2 = g²``.
    """
    center = np.asarray(center, dtype=np.float64).reshape(-1, 2)
    cov = np.asarray(cov, dtype=np.float64).reshape(-1, 2, 2)
    r2_arr = np.broadcast_to(np.asarray(r2, dtype=np.float64), (center.shape[0],))
    ok = _finite_rows(center, cov) & np.isfinite(r2_arr)
    if not ok.any():
        return image
    axes, angle = gate_ellipses(cov[ok], r2_arr[ok])
    polys = ellipse_polygons(center[ok], axes, angle)
    cv2.polylines(image, list(polys), True, color, thickness, cv2.LINE_AA)
    return image


def shown_gates(gates: GateRegions, tracks: TrackFrame,
                shown_ids: Callable[[NDArray[np.int64]], NDArray[np.int64]] | None = None,
                ) -> GateRegions:
    """The gates worth drawing: those of confirmed tracks (``track_id > 0``) with a box in
    ``tracks``, so that every drawn ellipse belongs to a drawn box.

    ``shown_ids`` maps the tracker's IDs to the IDs ``tracks`` show, where they differ (the
    video's relinking, :meth:`mvtrack.video.relink.Relinker.shown`): a relinked track keeps
    its gate, under its shown ID.
    """
    if shown_ids is not None:
        gates = dataclasses.replace(gates, track_id=shown_ids(gates.track_id))
    shown = np.isfinite(np.hstack([tracks.filtered_xy, tracks.wh])).all(axis=1)
    return gates.take((gates.track_id > 0) & np.isin(gates.track_id, tracks.track_id[shown]))


def draw_boxes(
    image: NDArray[np.uint8],
    tracks: TrackFrame,
    thickness: int = 2,
    labels: bool = True,
    blocked: NDArray[np.int64] | None = None,
) -> NDArray[np.uint8]:
    """Draw each track's box in its state colour, and ``ID`` (+ state letter) beside it.

    The labels stay inside the frame, off the ``blocked`` rectangles (``x0, y0, x1, y1``: the
    text header) and off each other (:func:`mvtrack.viz.labels.place_frame_labels`): above
    the box where there is room, else below or inside it.
    """
    if len(tracks) == 0:
        return image
    xy, wh = tracks.filtered_xy, tracks.wh
    ok = _finite_rows(xy, wh)
    polys = box_polygons(xy, wh)
    for state, color in STATE_COLORS.items():
        sel = ok & (tracks.state == state)
        if sel.any():
            cv2.polylines(image, list(polys[sel]), True, color, thickness, cv2.LINE_8)
    if labels and ok.any():
        h, w = image.shape[:2]
        scale = _text_scale(w, h)
        thick = 1 if scale < 0.6 else 2
        idx = np.flatnonzero(ok)
        texts = [f"{int(tracks.track_id[i])}{STATE_LABELS.get(int(tracks.state[i]), '?')}"
                 for i in idx]
        metrics = [cv2.getTextSize(t, cv2.FONT_HERSHEY_SIMPLEX, scale, thick) for t in texts]
        # the dark box _label fills: tw + 3 by th + base + 2 pixels
        sizes = np.array([[tw + 3, th + base + 2] for (tw, th), base in metrics], np.int64)
        box = np.concatenate([polys[idx, 0, :], polys[idx, 2, :]], axis=1)
        corners = place_frame_labels(box, sizes, (w, h), blocked)
        for k, i in enumerate(idx):  # one putText per label: OpenCV draws text one by one
            th = metrics[k][0][1]
            state = int(tracks.state[i])
            org = (int(corners[k, 0]) + 1, int(corners[k, 1]) + th + 2)  # the box at the corner
            _label(image, texts[k], org, scale, thick, STATE_COLORS.get(state, (255, 255, 255)))
    return image


def _text_scale(w: int, h: int) -> float:
    """Font scale: 0.4 at 320×240, growing with larger frames, smaller for tiny ones."""
    side = min(w, 4 * h / 3)
    return max(min(0.4, side / 800.0), side / 1100.0)


def _label_box(text: str, org: tuple[int, int], scale: float, thick: int) -> tuple[int, ...]:
    """``x0, y0, x1, y1`` of the dark box :func:`_label` draws behind ``text``."""
    (tw, th), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    x, y = org
    return (x - 1, y - th - 2, x + tw + 1, y + base - 1)


def _label(
    image: NDArray[np.uint8], text: str, org: tuple[int, int], scale: float, thick: int,
    color: tuple[int, int, int],
) -> None:
    """``text`` in ``color`` on a dark box (readable on any background), baseline at ``org``."""
    x0, y0, x1, y1 = _label_box(text, org, scale, thick)
    cv2.rectangle(image, (x0, y0), (x1, y1), (20, 20, 20), -1)
    cv2.putText(image, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, color, thick, cv2.LINE_AA)


class TrailBuffer:
    """The last ``length`` frames of tracks, turned into one polyline per track ID.

    Keeps whole :class:`TrackFrame` rows (no per-track objects); :meth:`polylines` stacks them
    and splits by ID with a sort.
    """

    def __init__(self, length: int = 30) -> None:
        if length < 2:
            raise ValueError(f"trail length must be at least 2, got {length}")
        self.length = length
        self._ids: deque[NDArray[np.int64]] = deque(maxlen=length)
        self._xy: deque[FloatArray] = deque(maxlen=length)

    def push(self, tracks: TrackFrame) -> None:
        """Add one frame's tracks (their filtered positions)."""
        self._ids.append(np.asarray(tracks.track_id, dtype=np.int64))
        self._xy.append(np.asarray(tracks.filtered_xy, dtype=np.float64).reshape(-1, 2))

    def polylines(self) -> tuple[NDArray[np.int64], list[NDArray[np.int32]]]:
        """The tracks of the newest frame with at least two points, and each one's points
        (oldest first); a track that has ended leaves no trail behind."""
        if not self._ids:
            return np.zeros(0, dtype=np.int64), []
        ids = np.concatenate(list(self._ids))
        xy = np.concatenate(list(self._xy))
        age = np.concatenate([np.full(len(a), k) for k, a in enumerate(self._ids)])
        ok = np.isfinite(xy).all(axis=1) & np.isin(ids, self._ids[-1])
        ids, xy, age = ids[ok], xy[ok], age[ok]
        if ids.size == 0:
            return ids, []
        order = np.lexsort((age, ids))
        ids, xy = ids[order], xy[order]
        uniq, start, count = np.unique(ids, return_index=True, return_counts=True)
        keep = count >= 2
        pts = np.rint(xy).astype(np.int32)
        lines = np.split(pts, start[1:])
        return uniq[keep], [line for line, k in zip(lines, keep, strict=True) if k]


def draw_trails(
    image: NDArray[np.uint8], trails: TrailBuffer, thickness: int = 1
) -> NDArray[np.uint8]:
    """Draw each track's recent path in its palette colour (one polylines call per colour)."""
    ids, lines = trails.polylines()
    if not lines:
        return image
    colour_idx = ids % len(TRAIL_PALETTE)
    for c in np.unique(colour_idx):
        sel = [lines[i] for i in np.flatnonzero(colour_idx == c)]
        color = tuple(int(v) for v in TRAIL_PALETTE[c])
        cv2.polylines(image, sel, False, color, thickness, cv2.LINE_AA)
    return image


def annotate_frame(
    frame: NDArray[np.uint8],
    tracks: TrackFrame,
    *,
    trails: TrailBuffer | None = None,
    gate_center: FloatArray | None = None,
    gate_cov: FloatArray | None = None,
    gate_r2: float | FloatArray | None = None,
    text: Sequence[str] = (),
) -> NDArray[np.uint8]:
    """A copy of ``frame`` (BGR or grey) with trails, gates, boxes, IDs and a text header.

    Parameters
    ----------
    frame : (H, W, 3) or (H, W) uint8
        The video frame.
    tracks : TrackFrame
        The tracker's output for this frame.
    trails : TrailBuffer, optional
        Recent positions (push ``tracks`` into it before calling).
    gate_center, gate_cov, gate_r2 : optional
        Gate regions to draw (see :func:`draw_gates`); skipped when ``gate_cov`` is None.
    text : sequence of str
        Lines written at the top left (frame number, settings).
    """
    img = frame.copy() if frame.ndim == 3 else cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if trails is not None:
        draw_trails(img, trails)
    if gate_cov is not None and gate_center is not None and gate_r2 is not None:
        draw_gates(img, gate_center, gate_cov, gate_r2)
    h, w = img.shape[:2]
    scale = _text_scale(w, h)
    step = round(35 * scale)
    header = [(line, (4, step + step * k)) for k, line in enumerate(text)]
    blocked = np.array([_label_box(line, org, scale, 1) for line, org in header],
                       np.int64).reshape(-1, 4)
    draw_boxes(img, tracks, blocked=blocked)  # the IDs kept clear of the header
    for line, org in header:
        _label(img, line, org, scale, 1, (255, 255, 255))
    return img
