"""Draw the analytics' scene on a frame: count lines, zones, approaches, running counts and
speeds (OpenCV, BGR, in place). Called by the annotated-video writer and the report."""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

Image = NDArray[np.uint8]

LINE_COLOR = (0, 215, 255)  # amber
ZONE_COLOR = (255, 160, 60)  # light blue
APPROACH_COLOR = (120, 200, 120)  # green


def _pt(p: NDArray[np.float64]) -> tuple[int, int]:
    return round(float(p[0])), round(float(p[1]))


def _label(img: Image, text: str, org: tuple[int, int], color: tuple[int, int, int],
           scale: float = 0.45) -> None:
    """Text with a dark outline, readable on any background."""
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), 3, cv2.LINE_AA)
    cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, color, 1, cv2.LINE_AA)


def draw_lines(img: Image, lines: Sequence[object],
               counts: dict[str, tuple[int, int]] | None = None) -> Image:
    """Each count line with an arrow towards its ``forward`` side and, if given, its counts
    ``(forward, backward)`` after the names of the two directions."""
    for line in lines:
        a, b = np.asarray(line.a), np.asarray(line.b)  # type: ignore[attr-defined]
        cv2.line(img, _pt(a), _pt(b), LINE_COLOR, 2, cv2.LINE_AA)
        mid, d = (a + b) / 2, b - a
        normal = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-9)  # right of a → b
        cv2.arrowedLine(img, _pt(mid), _pt(mid + 14 * normal), LINE_COLOR, 1, cv2.LINE_AA,
                        tipLength=0.4)
        name = line.name  # type: ignore[attr-defined]
        text = name
        if counts is not None and name in counts:
            f, bk = counts[name]
            fwd, back = getattr(line, "labels", ("forward", "backward"))
            text = f"{name}: {fwd} {f}, {back} {bk}"
        _label(img, text, _pt(a + np.array([4.0, -6.0])), LINE_COLOR)
    return img


def draw_zones(img: Image, zones: Sequence[object], occupancy: dict[str, int] | None = None,
               color: tuple[int, int, int] = ZONE_COLOR, alpha: float = 0.18) -> Image:
    """Each zone as a translucent polygon with its name (and its occupancy, if given)."""
    polys = [np.round(np.asarray(z.polygon)).astype(np.int32) for z in zones]  # type: ignore[attr-defined]
    if polys:  # blend within the zones' bounding box only (a frame-sized blend is 4x dearer)
        allp = np.concatenate(polys)
        h, w = img.shape[:2]
        x0, y0 = np.clip(allp.min(axis=0), 0, [w, h])
        x1, y1 = np.clip(allp.max(axis=0) + 1, 0, [w, h])
        if x1 > x0 and y1 > y0:
            roi = img[y0:y1, x0:x1]
            overlay = roi.copy()
            cv2.fillPoly(overlay, [(p - [x0, y0]).astype(np.int32) for p in polys], color)
            cv2.addWeighted(overlay, alpha, roi, 1 - alpha, 0, dst=roi)
    for zone in zones:
        poly = np.round(np.asarray(zone.polygon)).astype(np.int32)  # type: ignore[attr-defined]
        cv2.polylines(img, [poly], True, color, 1, cv2.LINE_AA)
        name = zone.name  # type: ignore[attr-defined]
        text = name if occupancy is None or name not in occupancy else (
            f"{name}: {occupancy[name]}")
        c = np.asarray(zone.centroid)  # type: ignore[attr-defined]
        _label(img, text, _pt(c - np.array([4.0 * len(text) / 2, 0.0])), color)
    return img


def draw_speeds(img: Image, xy: NDArray[np.float64], speed_kmh: NDArray[np.float64],
                stopped: NDArray[np.bool_] | None = None) -> Image:
    """Speed labels (km/h, ``stop`` for stopped rows) just below the given points."""
    for i, (p, v) in enumerate(zip(np.asarray(xy), np.asarray(speed_kmh), strict=True)):
        if not np.isfinite(v) or not np.isfinite(p).all():
            continue
        text = "stop" if stopped is not None and stopped[i] else f"{v:.0f} km/h"
        _label(img, text, _pt(p + np.array([-12.0, 14.0])), (255, 255, 255), 0.4)
    return img


def draw_scene(img: Image, settings: object, counts: dict[str, tuple[int, int]] | None = None,
               occupancy: dict[str, int] | None = None) -> Image:
    """Approaches, zones and lines of an :class:`~mvtrack.analytics.settings.
    AnalyticsSettings` on ``img`` (in place; returned)."""
    draw_zones(img, settings.approaches, None, APPROACH_COLOR, 0.12)  # type: ignore[attr-defined]
    draw_zones(img, settings.zones, occupancy)  # type: ignore[attr-defined]
    draw_lines(img, settings.lines, counts)  # type: ignore[attr-defined]
    return img
