"""Labels placed beside anchors of a figure so that they overlap no other label."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.viz.colors import halo

FloatArray = NDArray[np.float64]


def crowd_labels(
    anchors: FloatArray, texts: list[str], colors: list[object], radius: float,
    min_group: int = 4, shown: int = 3, mixed: object = "black",
) -> tuple[FloatArray, list[str], list[object]]:
    """One label for each crowd of anchors: ``min_group`` or more anchors within ``radius``
    (data units) of the crowd's first anchor become one label, ``"n tracks: a, b, c, …"`` with the
    first ``shown`` texts, at their mean, in their colour when they share one (else
    ``mixed``). The anchors are taken in the order given, each joining the first crowd it
    reaches; the others keep their own label.

    Where many short tracks end at one place (the fragments of a vehicle that waits, the
    tracks that leave at one point of the image's edge), their IDs would otherwise fan out
    around it on leader lines and hide the paths.
    """
    anchors = np.asarray(anchors, float).reshape(-1, 2)
    leaders: list[int] = []
    members: list[list[int]] = []
    for i, a in enumerate(anchors):
        near = [g for g, j in enumerate(leaders) if np.hypot(*(a - anchors[j])) <= radius]
        if near:
            members[near[0]].append(i)
        else:
            leaders.append(i)
            members.append([i])
    out_xy, out_text, out_color = [], [], []
    for group in members:
        if len(group) < min_group:
            for i in group:
                out_xy.append(anchors[i])
                out_text.append(texts[i])
                out_color.append(colors[i])
            continue
        names = [texts[i] for i in group]
        listed = ", ".join(names[:shown]) + (", …" if len(names) > shown else "")
        same = {repr(colors[i]) for i in group}
        out_xy.append(anchors[group].mean(axis=0))
        out_text.append(f"{len(group)} tracks: {listed}")
        out_color.append(colors[group[0]] if len(same) == 1 else mixed)
    return np.array(out_xy, float).reshape(-1, 2), out_text, out_color


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


def place_frame_labels(
    boxes: NDArray[np.int64],
    sizes: NDArray[np.int64],
    frame: tuple[int, int],
    blocked: NDArray[np.int64] | None = None,
) -> NDArray[np.int64]:
    """Top-left corners, in pixels, of one label per box of a video frame, each inside the
    frame and clear of the ``blocked`` rectangles (the frame's text header) and of the labels
    placed before it.

    A label is tried, in order, above its box (left-aligned, then right-aligned), below it
    (left, right), inside its top-left corner, left and right of its top edge, and (for a box
    hidden under the header) just below the ``blocked`` rectangles, each moved into the frame;
    it takes the first place that overlaps nothing (nor touches: a pixel apart, so two labels
    never read as one), else the one that overlaps least. Labels are placed from the top of the
    frame down (then left to right), so that two boxes side by side get two labels side by side
    or one above the other, never one over the other.

    Parameters
    ----------
    boxes : (K, 4) int
        ``x0, y0, x1, y1`` of each box.
    sizes : (K, 2) int
        Width and height of each label.
    frame : (W, H)
        Frame size.
    blocked : (B, 4) int, optional
        Rectangles ``x0, y0, x1, y1`` no label may cover.

    Returns
    -------
    (K, 2) int64
        ``x, y`` of each label's top-left corner, in the order of ``boxes``.
    """
    boxes = np.asarray(boxes, np.int64).reshape(-1, 4)
    sizes = np.asarray(sizes, np.int64).reshape(-1, 2)
    blocked = (np.zeros((0, 4), np.int64) if blocked is None
               else np.asarray(blocked, np.int64).reshape(-1, 4))
    below_blocked = int(blocked[:, 3].max()) + 2 if len(blocked) else 0

    # every label at its first place at once; only those that meet another or the header
    # look further, one at a time (a sparse scene has none)
    first = _inside(np.stack([boxes[:, 0], boxes[:, 1] - sizes[:, 1] - 1], axis=1), sizes,
                    frame)
    rects = np.concatenate([first, first + sizes], axis=1)
    clash = _overlap(rects, rects) > 0
    np.fill_diagonal(clash, False)
    moved = np.flatnonzero(clash.any(axis=1) | (_overlap(rects, blocked) > 0).any(axis=1))
    out = first.copy()
    if moved.size == 0:
        return out
    moved = moved[np.lexsort((boxes[moved, 0], boxes[moved, 1]))]
    x0, y0, x1, y1 = boxes[moved].T
    w, h = sizes[moved].T
    below = np.full_like(x0, below_blocked)
    cand = np.stack([  # (M, 9, 2), the places in the order they are tried
        np.stack([x0, y0 - h - 1], 1), np.stack([x1 - w, y0 - h - 1], 1),  # above
        np.stack([x0, y1 + 1], 1), np.stack([x1 - w, y1 + 1], 1),  # below
        np.stack([x0 + 1, y0 + 1], 1),  # inside the top-left corner
        np.stack([x0 - w - 1, y0], 1), np.stack([x1 + 1, y0], 1),  # beside the top edge
        np.stack([x0, below], 1), np.stack([x1 - w, below], 1),  # a box under the header
    ], axis=1)
    cand = _inside(cand, sizes[moved][:, None, :], frame)
    cand_rects = np.concatenate([cand, cand + sizes[moved][:, None, :]], axis=2)
    taken = np.zeros((len(blocked) + len(boxes), 4), np.int64)
    fixed = np.vstack([blocked, np.delete(rects, moved, axis=0)])
    n = len(fixed)
    taken[:n] = fixed
    for j, i in enumerate(moved):  # one label at a time: each sees those placed before
        best = int(np.argmin(_overlap(cand_rects[j], taken[:n]).sum(axis=1)))
        out[i] = cand[j, best]
        taken[n] = cand_rects[j, best]
        n += 1
    return out


def _inside(corner: NDArray[np.int64], size: NDArray[np.int64],
            frame: tuple[int, int]) -> NDArray[np.int64]:
    """Top-left ``corner`` of labels of ``size`` moved into the ``frame`` (W, H)."""
    hi = np.maximum(np.asarray(frame, np.int64) - size, 0)
    return np.clip(corner, 0, hi)


def _overlap(a: NDArray[np.int64], b: NDArray[np.int64]) -> NDArray[np.int64]:
    """(len(a), len(b)) areas of the rectangles ``x0, y0, x1, y1`` of ``a`` and ``b``, each
    grown by a pixel (touching counts: two labels must be a pixel apart)."""
    ox = (np.minimum(a[:, None, 2], b[None, :, 2]) + 1
          - np.maximum(a[:, None, 0], b[None, :, 0])).clip(0)
    oy = (np.minimum(a[:, None, 3], b[None, :, 3]) + 1
          - np.maximum(a[:, None, 1], b[None, :, 1])).clip(0)
    return ox * oy
