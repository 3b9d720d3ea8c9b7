"""The objects of a simulated frame, drawn with OpenCV at sub-pixel precision.

Vehicles are two-tone rotated bodies with a shaded side (:func:`draw_vehicle`), people blobs
with head, torso and legs (:func:`draw_person`), points dots (:func:`draw_point`), X4's
vehicles and crowd targets plain boxes (:func:`draw_block`). Each takes the arrays of one
frame's objects of its kind; vertices are in OpenCV's fixed point (:data:`SHIFT` bits).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

Frame = NDArray[np.uint8]
SHIFT = 4  # OpenCV fixed-point bits: sub-pixel vertices at 1/16 px
ONE = 1 << SHIFT
#: how :func:`~mvtrack.sim.render.render_frames` draws each kind of object: 0 and 4 boxes,
#: 1 vehicles, 2 people, 3 points
KIND_CODE = {"block": 0, "vehicle": 1, "motorcycle": 1, "person": 2, "point": 3, "box": 4}


def fill_poly(img: Frame, pts: NDArray[np.float64], color: tuple[int, ...]) -> None:
    """Fill the convex polygon ``pts`` (px, sub-pixel) with ``color``."""
    cv2.fillConvexPoly(img, np.round(pts * ONE).astype(np.int32), color, cv2.LINE_8, SHIFT)


def corners(xy: NDArray[np.float64], hd: NDArray[np.float64],
            x0: float, x1: float, y0: float, y1: float,
            lw: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 4, 2) corners of the local rectangles ``[x0, x1]·L × [y0, y1]·W`` of n bodies."""
    c, s = np.cos(hd)[:, None], np.sin(hd)[:, None]
    lx = np.array([x0, x1, x1, x0])[None] * lw[:, :1]
    ly = np.array([y0, y0, y1, y1])[None] * lw[:, 1:]
    return np.stack([xy[:, :1] + c * lx - s * ly, xy[:, 1:] + s * lx + c * ly], axis=-1)


def draw_vehicle(img: Frame, xy: NDArray[np.float64], hd: NDArray[np.float64],
                 lw: NDArray[np.float64], col: NDArray[np.uint8],
                 col2: NDArray[np.uint8]) -> None:
    """Two-tone bodies: body, a shaded right side, and a cabin (windows) of the second tone."""
    inner = np.maximum(lw - 1.0, 1.0)  # pixel centres: a body L px long covers L pixels
    polys = np.stack([
        corners(xy, hd, -0.5, 0.5, -0.5, 0.5, inner),  # body
        corners(xy, hd, -0.5, 0.5, 0.3, 0.5, inner),  # shaded right side
        corners(xy, hd, -0.3, 0.15, -0.32, 0.32, inner),  # cabin
    ], axis=1)
    ipolys = np.round(polys * ONE).astype(np.int32)
    tones = np.stack([col, (col.astype(np.float64) * 0.85).astype(np.uint8), col2], 1).tolist()
    for i in range(xy.shape[0]):  # the few vehicles of one frame
        for j in range(3):
            cv2.fillConvexPoly(img, ipolys[i, j], tones[i][j], cv2.LINE_8, SHIFT)


def draw_block(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
               col: NDArray[np.uint8]) -> None:
    """Plain axis-aligned rectangles (X4's vehicles, crowd targets)."""
    pts = corners(xy, np.zeros(xy.shape[0]), -0.5, 0.5, -0.5, 0.5, np.maximum(wh - 1.0, 1.0))
    ipts = np.round(pts * ONE).astype(np.int32)
    for i in range(xy.shape[0]):
        cv2.fillConvexPoly(img, ipts[i], tuple(int(v) for v in col[i]), cv2.LINE_8, SHIFT)


_SKIN = (120, 160, 205)


def draw_person(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
                col: NDArray[np.uint8], col2: NDArray[np.uint8]) -> None:
    """A small blob: head, torso (main tone) and legs (second tone) inside the box."""
    w, h = wh[:, 0], wh[:, 1]
    head_r = np.maximum(0.3 * w, 1.0)
    head = np.stack([xy[:, 0], xy[:, 1] - h / 2 + head_r + 0.5], -1)
    torso = np.stack([xy[:, 0], xy[:, 1] - 0.06 * h], -1)
    axes = np.stack([np.maximum(w / 2 - 0.5, 1.0), 0.28 * h], -1)
    legs = corners(np.stack([xy[:, 0], xy[:, 1] + 0.3 * h], -1), np.zeros(xy.shape[0]),
                   -0.5, 0.5, -0.5, 0.5, np.stack([0.75 * w, 0.4 * h - 1.0], -1))
    to_i = lambda a: np.round(a * ONE).astype(np.int32)  # noqa: E731
    head_i, torso_i, axes_i, legs_i = to_i(head), to_i(torso), to_i(axes), to_i(legs)
    r_i = to_i(head_r)
    for i in range(xy.shape[0]):
        cv2.fillConvexPoly(img, legs_i[i], tuple(int(v) for v in col2[i]), cv2.LINE_8, SHIFT)
        cv2.ellipse(img, tuple(torso_i[i]), tuple(axes_i[i]), 0.0, 0.0, 360.0,
                    tuple(int(v) for v in col[i]), -1, cv2.LINE_8, SHIFT)
        cv2.circle(img, tuple(head_i[i]), int(r_i[i]), _SKIN, -1, cv2.LINE_8, SHIFT)


def draw_point(img: Frame, xy: NDArray[np.float64], wh: NDArray[np.float64],
               col: NDArray[np.uint8]) -> None:
    """Filled discs of diameter the smaller side of each box."""
    r = np.round(np.maximum(wh.min(axis=1) / 2, 1.0) * ONE).astype(np.int32)
    c = np.round(xy * ONE).astype(np.int32)
    for i in range(xy.shape[0]):
        cv2.circle(img, tuple(c[i]), int(r[i]), tuple(int(v) for v in col[i]), -1,
                   cv2.LINE_8, SHIFT)
