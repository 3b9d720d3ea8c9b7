"""Labels placed beside anchors of a figure so that they overlap no other label."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.viz.colors import halo

FloatArray = NDArray[np.float64]


def place_labels(
    ax,
    anchors: FloatArray,
    texts: list[str],
    colors: list[object] | None = None,
    fontsize: float = 7.0,
    max_radius: float = 48.0,
) -> list:
    """Put one text per anchor (data coordinates) where it overlaps no other label.

    Each label is tried at offsets of growing radius (points) in sixteen directions around its
    anchor, the text extending away from the anchor, and placed at the first position whose
    box lies inside the axes and clear of the labels placed before it; a label that finds no
    place within ``max_radius`` points is left out. A label moved away from its anchor is joined
    to it by a thin line.

    Returns
    -------
    list of matplotlib.text.Annotation
        The labels placed (fewer than ``texts`` when some found no room).
    """
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    # an axes with a fixed aspect (imshow) takes its final box only when drawn: place the
    # labels in that box, not in the one before the aspect is applied
    ax.apply_aspect()
    inside = ax.get_window_extent(renderer)
    px = fig.dpi / 72.0
    colors = colors if colors is not None else ["black"] * len(texts)
    angles = np.arange(16) * (np.pi / 8) + np.pi / 4
    radii = np.arange(3.0, max_radius + 1e-9, 3.0)
    offs = (radii[:, None, None] * np.stack([np.cos(angles), np.sin(angles)], -1)[None]).reshape(
        -1, 2)  # (candidates, 2) in points, nearest first
    taken = np.zeros((0, 4))  # x0, y0, x1, y1 of placed labels, display pixels
    placed = []
    anchors = np.asarray(anchors, float).reshape(-1, 2)
    for xy, text, color in zip(anchors, texts, colors, strict=True):
        probe = ax.text(0, 0, text, fontsize=fontsize)
        ext = probe.get_window_extent(renderer)
        probe.remove()
        w, h = ext.width + 2.0, ext.height + 2.0
        ax_xy = ax.transData.transform(xy)
        d = offs * px
        # the text extends away from its anchor: left/right/centre by the offset's direction
        sx = np.sign(np.round(offs[:, 0] / np.maximum(np.abs(offs).max(axis=1), 1e-9), 1))
        sy = np.sign(np.round(offs[:, 1] / np.maximum(np.abs(offs).max(axis=1), 1e-9), 1))
        x0 = ax_xy[0] + d[:, 0] - w * (1 - sx) / 2
        y0 = ax_xy[1] + d[:, 1] - h * (1 - sy) / 2
        box = np.stack([x0, y0, x0 + w, y0 + h], axis=1)
        ok = ((box[:, 0] >= inside.x0) & (box[:, 2] <= inside.x1) & (box[:, 1] >= inside.y0)
              & (box[:, 3] <= inside.y1))
        if taken.size:
            hit = ((box[:, None, 0] < taken[None, :, 2]) & (box[:, None, 2] > taken[None, :, 0])
                   & (box[:, None, 1] < taken[None, :, 3]) & (box[:, None, 3] > taken[None, :, 1]))
            ok &= ~hit.any(axis=1)
        if not ok.any():
            continue
        i = int(np.argmax(ok))
        ha = {1.0: "left", -1.0: "right", 0.0: "center"}[float(sx[i])]
        va = {1.0: "bottom", -1.0: "top", 0.0: "center"}[float(sy[i])]
        far = radii[i // len(angles)] > 3.0
        ann = ax.annotate(
            text, xy, xytext=tuple(offs[i]), textcoords="offset points", fontsize=fontsize,
            color=color, ha=ha, va=va, path_effects=halo(2.5), zorder=6,  # over the paths
            arrowprops={"arrowstyle": "-", "color": color, "lw": 0.6, "shrinkA": 0,
                        "shrinkB": 0} if far else None,
        )
        taken = np.vstack([taken, box[i]])
        placed.append(ann)
    return placed
