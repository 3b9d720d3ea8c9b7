"""Plots of a tracking run: trajectories over the scene, track lengths, tracks per frame.

The functions take the stacked output rows of a run (:class:`TrackRows`, built once from the
per-frame :class:`~mvtrack.types.TrackFrame` objects) and return matplotlib Figures; the
caller saves them (atomically, :func:`save_figure`). Matplotlib is used with the Agg backend
through its object API (no global pyplot state). The colours are in :mod:`mvtrack.viz.colors`
and the placement of labels in :mod:`mvtrack.viz.labels` (both names also importable from here).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.io.atomic import atomic_path
from mvtrack.types import TrackFrame, TrackState
from mvtrack.viz.colors import (
    FAILURE_COLOR,
    PALETTE,
    TRUTH_COLOR,
    contrast_ratio,
    halo,
    relative_luminance,
)
from mvtrack.viz.labels import crowd_labels, place_labels

__all__ = [
    "FAILURE_COLOR",
    "PALETTE",
    "TRUTH_COLOR",
    "TrackRows",
    "contrast_ratio",
    "grouped_bars",
    "halo",
    "place_labels",
    "relative_luminance",
    "save_figure",
    "track_length_figure",
    "tracks_per_frame_figure",
    "trajectory_figure",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class TrackRows:
    """All output rows of a run, stacked: ``R`` rows of (frame, id, state, xy, wh)."""

    frame: IntArray
    track_id: IntArray
    state: IntArray
    xy: FloatArray
    wh: FloatArray

    @classmethod
    def from_frames(cls, frames: Iterable[TrackFrame]) -> TrackRows:
        """Stack per-frame tracker outputs (filtered positions)."""
        frames = [f for f in frames if len(f)]
        if not frames:
            zi = np.zeros(0, dtype=np.int64)
            return cls(zi, zi.copy(), zi.copy(), np.zeros((0, 2)), np.zeros((0, 2)))
        return cls(
            frame=np.concatenate([np.full(len(f), f.frame, dtype=np.int64) for f in frames]),
            track_id=np.concatenate([f.track_id for f in frames]).astype(np.int64),
            state=np.concatenate([f.state for f in frames]).astype(np.int64),
            xy=np.concatenate([f.filtered_xy for f in frames]).reshape(-1, 2),
            wh=np.concatenate([f.wh for f in frames]).reshape(-1, 2),
        )

    def __len__(self) -> int:
        return int(self.frame.shape[0])

    def split(self) -> tuple[IntArray, list[FloatArray], list[IntArray]]:
        """Track IDs, and per track its positions and frames in time order."""
        if len(self) == 0:
            return np.zeros(0, dtype=np.int64), [], []
        order = np.lexsort((self.frame, self.track_id))
        ids = self.track_id[order]
        uniq, start = np.unique(ids, return_index=True)
        return uniq, np.split(self.xy[order], start[1:]), np.split(self.frame[order], start[1:])

    def lengths(self) -> tuple[IntArray, IntArray]:
        """Track IDs and the number of frames each was output in."""
        return np.unique(self.track_id, return_counts=True)  # type: ignore[return-value]

    def state_histogram(self) -> dict[str, int]:
        """Number of output rows per life-cycle state name."""
        counts = np.bincount(self.state, minlength=len(TrackState))
        return {s.name.lower(): int(counts[s]) for s in TrackState if s != TrackState.DELETED}


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def trajectory_figure(
    rows: TrackRows,
    size: tuple[int, int],
    background: NDArray[np.uint8] | None = None,
    title: str = "",
    min_length: int = 1,
    *,
    truth: dict[str, FloatArray] | None = None,
    groups: dict[int, str] | None = None,
    group_colors: dict[str, object] | None = None,
    labels: bool = True,
    legend_title: str | None = None,
    failure_group: str = "spurious",
):
    """Every track's path over the scene (image coordinates, y down), labelled with its ID.

    The scene is drawn in grey and every path over a white halo, so that each colour reads on
    any background; labels are placed so that they do not overlap
    (:func:`~mvtrack.viz.labels.place_labels`).

    Parameters
    ----------
    rows : TrackRows
        Output rows of the run.
    size : (W, H)
        Image size in pixels.
    background : (H, W, 3) uint8 BGR, optional
        A frame drawn in grey under the paths.
    title : str
        Axes title.
    min_length : int
        Tracks output in fewer frames are left out.
    truth : dict of str to (T, 2) arrays, optional
        True paths by name, drawn as dashed black lines beside the estimates.
    groups : dict of int to str, optional
        Group (legend entry) of each track ID, e.g. the object it follows; tracks missing from
        it are drawn in their ID's palette colour without a legend entry.
    group_colors : dict of str to colour, optional
        Colour of each group (default: the palette in the groups' natural order, e.g. V1, V2,
        …, V10; :data:`~mvtrack.viz.colors.FAILURE_COLOR` and a dotted line for ``failure_group``).
    labels : bool
        Label each path's end with its track ID; four or more paths ending within 2 % of the
        image of one another share one label, their number and first IDs
        (:func:`~mvtrack.viz.labels.crowd_labels`).
    legend_title : str, optional
        Title of the legend (shown when ``groups`` or ``truth`` is given).
    failure_group : str
        The group of tracks that follow nothing (drawn grey and dotted, listed last).
    """
    from matplotlib.lines import Line2D

    w, h = size
    fig = _figure(8.0, 8.0 * h / max(w, 1) + 0.9)
    ax = fig.add_subplot(1, 1, 1)
    if background is not None:
        grey = background.mean(axis=2) if background.ndim == 3 else background
        # the scene in light grey: the palette keeps a contrast ≥ 3:1 against a road of grey ≥ 96
        ax.imshow(0.3 * grey.astype(float) + 0.7 * 255.0, extent=(0, w, h, 0), cmap="gray",
                  vmin=0, vmax=255, interpolation="nearest")
    handles: list = []
    for k, path in enumerate((truth or {}).values()):
        path = np.asarray(path, float)
        ax.plot(path[:, 0], path[:, 1], ls=(0, (3, 2)), color=TRUTH_COLOR, lw=0.9, zorder=3,
                path_effects=halo(2.2))
        if k == 0:
            handles.append(Line2D([], [], ls=(0, (3, 2)), color=TRUTH_COLOR, lw=0.9,
                                  label="truth (dashed)"))
    ids, paths, _ = rows.split()
    keep = [i for i, p in enumerate(paths) if len(p) >= min_length]
    colors: dict[str, object] = dict(group_colors or {})
    used = sorted({groups[int(ids[i])] for i in keep if int(ids[i]) in groups}
                  if groups is not None else set(), key=_natural)
    used = [g for g in used if g != failure_group] + (
        [failure_group] if failure_group in used else [])
    for g in used:
        if g not in colors:
            colors[g] = FAILURE_COLOR if g == failure_group else PALETTE[
                sum(1 for c in colors if c != failure_group) % len(PALETTE)]
    track_color = []
    for i in keep:
        g = groups.get(int(ids[i])) if groups is not None else None
        track_color.append(colors[g] if g is not None else PALETTE[int(ids[i]) % len(PALETTE)])
    for k, i in enumerate(keep):
        g = groups.get(int(ids[i])) if groups is not None else None
        ax.plot(paths[i][:, 0], paths[i][:, 1], color=track_color[k], lw=1.6, zorder=4,
                ls=":" if g == failure_group else "-", path_effects=halo(3.4))
        ax.plot(*paths[i][0], "o", ms=3.2, color=track_color[k], zorder=5)
    for g in used:
        handles.append(Line2D([], [], color=colors[g], lw=1.6,
                              ls=":" if g == failure_group else "-", label=g))
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.set_aspect("equal")
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    ax.set_title(title or f"{len(keep)} tracks")
    if handles:
        ax.legend(handles=handles, title=legend_title, fontsize=7, title_fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False)
    fig.tight_layout()
    if labels and keep:
        ends = []
        for i in keep:  # the last point of each path inside the image
            p = paths[i]
            seen = np.flatnonzero((p[:, 0] >= 0) & (p[:, 0] <= w) & (p[:, 1] >= 0)
                                  & (p[:, 1] <= h))
            ends.append(p[seen[-1]] if seen.size else np.clip(p[-1], 0, [w, h]))
        # many paths ending at one spot (2 % of the image): one label "n tracks: a, b, …"
        xy, texts, cols = crowd_labels(np.array(ends), [str(int(ids[i])) for i in keep],
                                       track_color, 0.02 * max(w, h), mixed=TRUTH_COLOR)
        place_labels(ax, xy, texts, cols)
    return fig


def _natural(text: str) -> list:
    """Sort key that orders embedded numbers by value (V2 before V10)."""
    import re

    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", text)]


def grouped_bars(
    ax,
    categories: list[str],
    series: dict[str, list[float]],
    *,
    errors: dict[str, list[tuple[float, float]]] | None = None,
    colors: dict[str, object] | None = None,
    hatches: dict[str, str] | None = None,
    value_labels: bool = True,
    fmt: str = "{:.3g}",
    missing: str = "n/a",
):
    """Grouped bars: one group per category, one bar per series, with optional error bars.

    Parameters
    ----------
    categories : list of str
        Tick labels (one group of bars each).
    series : dict of str to list of float
        Bar heights per series, in category order; NaN draws no bar and writes ``missing``.
    errors : dict of str to list of (low, high), optional
        Interval per bar (e.g. a 95 % binomial interval), drawn as an error bar.
    colors, hatches : dict, optional
        Per series (default colours: :data:`~mvtrack.viz.colors.PALETTE` in order).
    value_labels : bool
        Write each bar's value above it.

    Returns
    -------
    dict of str to matplotlib.container.BarContainer
    """
    n = len(series)
    width = 0.8 / max(n, 1)
    x = np.arange(len(categories), dtype=float)
    out = {}
    top = 0.0
    for k, (name, values) in enumerate(series.items()):
        v = np.asarray(values, float)
        pos = x + (k - (n - 1) / 2) * width
        color = (colors or {}).get(name, PALETTE[k % len(PALETTE)])
        bars = ax.bar(pos, np.nan_to_num(v), width * 0.92, label=name, color=color,
                      hatch=(hatches or {}).get(name), edgecolor="black", linewidth=0.6)
        out[name] = bars
        hi = v.copy()
        if errors is not None and name in errors:
            iv = np.asarray(errors[name], float).reshape(-1, 2)
            yerr = np.stack([v - iv[:, 0], iv[:, 1] - v])
            ok = np.isfinite(v)
            ax.errorbar(pos[ok], v[ok], yerr=yerr[:, ok], fmt="none", ecolor="black",
                        elinewidth=1.0, capsize=3, zorder=5)
            hi = np.where(ok, np.maximum(v, iv[:, 1]), v)
        top = max(top, float(np.nanmax(hi, initial=0.0)))
        if value_labels:
            for p, val, h in zip(pos, v, hi, strict=True):
                text = missing if not np.isfinite(val) else fmt.format(val)
                ax.annotate(text, (p, 0.0 if not np.isfinite(h) else h), xytext=(0, 2),
                            textcoords="offset points", ha="center", va="bottom", fontsize=6.5,
                            rotation=90 if n > 3 else 0)
    ax.set_xticks(x, categories)
    ax.set_xlim(-0.6, len(categories) - 0.4)
    ax.set_ylim(0.0, top * 1.25 if top > 0 else 1.0)
    return out


def track_length_figure(rows: TrackRows, fps: float, title: str = ""):
    """Histogram of track lengths (frames) of a run."""
    fig = _figure(6.0, 3.5)
    ax = fig.add_subplot(1, 1, 1)
    _, lengths = rows.lengths()
    if len(lengths):
        ax.hist(lengths, bins=min(30, max(5, len(lengths) // 2)), color="tab:blue")
    ax.set_xlabel(f"track length (frames at {fps:g} fps)")
    ax.set_ylabel("tracks")
    ax.set_title(title or f"{len(lengths)} tracks")
    fig.tight_layout()
    return fig


def tracks_per_frame_figure(rows: TrackRows, n_frames: int, title: str = ""):
    """Number of output tracks per frame, split by life-cycle state (stacked areas)."""
    fig = _figure(7.0, 3.2)
    ax = fig.add_subplot(1, 1, 1)
    n = max(n_frames, int(rows.frame.max()) + 1 if len(rows) else 0)
    x = np.arange(n)
    stacks, labels = [], []
    for s in (TrackState.CONFIRMED, TrackState.COASTING, TrackState.STOPPED, TrackState.TENTATIVE):
        sel = rows.state == s
        stacks.append(np.bincount(rows.frame[sel], minlength=n)[:n])
        labels.append(s.name.lower())
    ax.stackplot(x, *stacks, labels=labels)
    ax.set_xlabel("frame")
    ax.set_ylabel("tracks")
    ax.legend(loc="upper right", fontsize=7)
    ax.set_title(title)
    fig.tight_layout()
    return fig


def save_figure(fig, dest: str | os.PathLike[str], dpi: int = 110) -> None:
    """Save ``fig`` to ``dest`` atomically (PNG by suffix)."""
    with atomic_path(dest) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
