"""Detection-level simulation: noisy, incomplete, cluttered detections from a scene's truth.

The model of issue 3's benchmark scene: every visible object is detected with probability
``1 − miss``, its centre perturbed by N(0, pos_sigma²) and its size by N(0, size_sigma²) per
axis; Poisson(``clutter``) false alarms per frame fall uniformly in the image with sizes
drawn from the scene's own boxes; rows are shuffled within each frame. All rows of all frames
are drawn at once (no loop per object).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mvtrack.sim.scene import Scene
from mvtrack.types import Detections

IntArray = NDArray[np.int64]


def detections_with_truth(
    scene: Scene,
    rng: np.random.Generator,
    pos_sigma: float = 2.0,
    size_sigma: float = 1.0,
    miss: float = 0.1,
    clutter: float = 3.0,
    shuffle: bool = True,
) -> tuple[list[Detections], list[IntArray]]:
    """Simulated detections per frame and, aligned with their rows, the true object ids.

    Parameters
    ----------
    scene : Scene
        Ground truth; only rows with ``scene.visible`` are detected.
    rng : numpy.random.Generator
        Source of all randomness.
    pos_sigma, size_sigma : float
        Standard deviation (px) of the centre noise and of the size noise, per axis.
    miss : float
        Probability that a visible object is not detected in a frame, in [0, 1].
    clutter : float
        Mean number of false alarms per frame (Poisson), uniform over the image.
    shuffle : bool
        Shuffle the rows within each frame (otherwise true detections come in id order,
        false alarms last).

    Returns
    -------
    dets : list of Detections
        One per frame ``0 .. scene.n_frames-1``; sizes are at least 1 px.
    ids : list of (M,) int64
        The object id of each detection row, ``-1`` for false alarms.
    """
    for name, value in (("pos_sigma", pos_sigma), ("size_sigma", size_sigma),
                        ("clutter", clutter)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f"{name} must be a finite number >= 0, got {value}")
    if not 0.0 <= miss <= 1.0:
        raise ValueError(f"miss must be in [0, 1], got {miss}")
    vis = np.flatnonzero(scene.visible)
    hit = vis[rng.random(vis.shape[0]) >= miss]
    k = hit.shape[0]
    frame_t = scene.frame[hit]
    xy_t = scene.xy[hit] + pos_sigma * rng.standard_normal((k, 2))
    wh_t = scene.wh[hit] + size_sigma * rng.standard_normal((k, 2))

    n_fa = rng.poisson(clutter, scene.n_frames)
    c = int(n_fa.sum())
    frame_c = np.repeat(np.arange(scene.n_frames, dtype=np.int64), n_fa)
    xy_c = rng.uniform(0.0, 1.0, (c, 2)) * np.array(scene.size, dtype=np.float64)
    if vis.shape[0]:  # false alarms look like the scene's objects
        wh_c = scene.wh[vis[rng.integers(0, vis.shape[0], c)]].copy()
    else:
        wh_c = np.full((c, 2), 10.0)
    wh_c += size_sigma * rng.standard_normal((c, 2))

    frame = np.concatenate([frame_t, frame_c])
    xy = np.concatenate([xy_t, xy_c])
    wh = np.maximum(np.concatenate([wh_t, wh_c]), 1.0)
    ids = np.concatenate([scene.id[hit], np.full(c, -1, np.int64)])
    # Random order first, then a stable sort by frame: shuffled within each frame.
    perm = rng.permutation(frame.shape[0]) if shuffle else np.arange(frame.shape[0])
    small = np.int16 if scene.n_frames < 2**15 else np.int64  # int16: NumPy's radix sort
    order = perm[np.argsort(frame[perm].astype(small), kind="stable")]
    frame, xy, wh, ids = frame[order], xy[order], wh[order], ids[order]
    bounds = np.searchsorted(frame, np.arange(scene.n_frames + 1))
    dets, truth = [], []
    for f in range(scene.n_frames):  # slicing per frame; no work per object
        a, b = bounds[f], bounds[f + 1]
        dets.append(Detections(f, xy[a:b], wh[a:b]))
        truth.append(ids[a:b])
    return dets, truth


def detections_from_scene(
    scene: Scene,
    rng: np.random.Generator,
    pos_sigma: float = 2.0,
    size_sigma: float = 1.0,
    miss: float = 0.1,
    clutter: float = 3.0,
    shuffle: bool = True,
) -> list[Detections]:
    """Simulated detections, one :class:`~mvtrack.types.Detections` per frame.

    Same draws as :func:`detections_with_truth` (which see for the parameters), without the
    true ids.
    """
    return detections_with_truth(scene, rng, pos_sigma, size_sigma, miss, clutter, shuffle)[0]

