"""Plots of a tracking run: trajectories over the scene, track lengths, tracks per frame.

The functions take the stacked output rows of a run (:class:`TrackRows`, built once from the
per-frame :class:`~mvtrack.types.TrackFrame` objects) and return matplotlib Figures; the
caller saves them (atomically, :func:`save_figure`). Matplotlib is used with the Agg backend
through its object API (no global pyplot state).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.io.atomic import atomic_path
from mvtrack.types import TrackFrame, TrackState

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
):
    """Every track's path over the scene (image coordinates, y down), labelled with its ID.

    Parameters
    ----------
    rows : TrackRows
        Output rows of the run.
    size : (W, H)
        Image size in pixels.
    background : (H, W, 3) uint8 BGR, optional
        A frame drawn faintly under the paths.
    title : str
        Axes title.
    min_length : int
        Tracks output in fewer frames are left out.
    """
    from matplotlib.collections import LineCollection

    w, h = size
    fig = _figure(8.0, 8.0 * h / max(w, 1) + 0.4)
    ax = fig.add_subplot(1, 1, 1)
    if background is not None:
        ax.imshow(background[..., ::-1] if background.ndim == 3 else background,
                  extent=(0, w, h, 0), alpha=0.45, cmap="gray")
    ids, paths, _ = rows.split()
    keep = [i for i, p in enumerate(paths) if len(p) >= min_length]
    if keep:
        cmap = _cmap()
        colors = cmap(np.asarray(ids)[keep] % 20)
        ax.add_collection(LineCollection([paths[i] for i in keep], colors=colors, linewidths=1.4))
        ends = np.array([paths[i][-1] for i in keep])
        starts = np.array([paths[i][0] for i in keep])
        ax.scatter(starts[:, 0], starts[:, 1], s=8, c=colors, marker="o")
        for k, i in enumerate(keep):  # one label per track, offline plot
            ax.annotate(str(int(ids[i])), ends[k], fontsize=7, color=colors[k])
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.set_aspect("equal")
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    ax.set_title(title or f"{len(keep)} tracks")
    fig.tight_layout()
    return fig


def _cmap():
    from matplotlib import colormaps

    return colormaps["tab20"]


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
