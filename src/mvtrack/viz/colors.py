"""Colours of the figures: the palette, the failure and truth colours, WCAG contrast, halos.

:data:`PALETTE` is read by every figure of :mod:`mvtrack.viz.plots` and of the experiments'
reports; :func:`contrast_ratio` is how its contrast against a scene drawn in light grey is
checked, and :func:`halo` keeps a line or a text readable over any background.
"""

from __future__ import annotations

import numpy as np

#: Dark, distinct qualitative colours (ColorBrewer's diverging schemes' dark ends): each has a
#: WCAG contrast of at least 3:1 against the light grey of a scene drawn by
#: :func:`~mvtrack.viz.plots.trajectory_figure` (grey level ≥ 200 for a road of grey 96 or
#: brighter).
PALETTE = (
    "#2166AC",  # blue
    "#B2182B",  # red
    "#1B7837",  # green
    "#762A83",  # purple
    "#8C510A",  # brown
    "#01665E",  # teal
    "#C51B7D",  # magenta
    "#6B6B00",  # olive
    "#08306B",  # navy
    "#A63603",  # dark orange
)
#: Colour of tracks and bars that stand for a failure or for nothing (spurious tracks).
FAILURE_COLOR = "#595959"
#: Colour of the ground truth drawn beside the estimates.
TRUTH_COLOR = "#000000"


def relative_luminance(color: object) -> float:
    """WCAG 2.x relative luminance of a colour (any matplotlib colour specification)."""
    from matplotlib.colors import to_rgb

    c = np.asarray(to_rgb(color))
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(lin @ [0.2126, 0.7152, 0.0722])


def contrast_ratio(a: object, b: object) -> float:
    """WCAG contrast ratio (1 … 21) of two colours."""
    la, lb = sorted((relative_luminance(a), relative_luminance(b)), reverse=True)
    return (la + 0.05) / (lb + 0.05)


def halo(width: float = 3.0, color: str = "white") -> list:
    """Path effects that draw a line or text over a wider ``color`` stroke: readable on any
    background."""
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=width, foreground=color)]
