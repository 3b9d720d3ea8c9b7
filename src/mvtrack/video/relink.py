r"""A track that ends behind an occluder and a new one that starts where it should reappear,
looking the same, are one object: the new one takes the old ID (online, in the video loop).

The tracker ends a track once its prediction is too uncertain to tell it from a neighbour
(``lost_std``) or after ``max_misses`` frames without a detection; a person hidden by a lamp
post for longer comes back as a new track. :class:`Relinker` keeps the confirmed tracks that
ended in the last ``window`` seconds (their last position ``x``, velocity ``v`` and box, and
an appearance: the colour histogram ``a`` of their measured boxes, an exponential average).
When a new public ID appears in frame ``k``, it is compared with every track that ended at
frame ``k_e`` within the window:

- **motion**: the new centre ``z`` lies within ``reach`` times the taller of the two boxes,
  plus ``spread`` times it per second hidden, of the ended track's extrapolation,
  :math:`\|z - (x + v (k - k_e))\| \le (\rho + \sigma (k - k_e) / f) \max(h, h')` at
  ``f`` frames per second (a walker hidden longer may have slowed down or turned back),
  with ``v`` the track's mean velocity over its last one to two seconds of output rows (the
  filter's last velocity is distorted as the object disappears behind the occluder: its box
  shrinks from one side);
- **size**: the heights differ by at most the factor ``size_ratio`` (the ended track's height
  averaged over its measured rows like its appearance: its last box shrinks as it disappears;
  the new track's first box), and ``h``, ``h'`` above are these heights;
- **appearance**: the Bhattacharyya coefficient of the histograms,
  :math:`\sum_b \sqrt{a_b a'_b} \ge` ``min_similarity``.

Among the pairs that pass, one assignment minimising
:math:`\|z - \hat x\| / (\rho \max(h, h')) + (1 - \mathrm{BC})` links each new track to at
most one ended track, which then leaves the gallery; the new track's rows carry the old ID
from its first one on (it had none before: tentative rows are not output). Nothing is
rewritten afterwards, so the annotated video, ``results.txt`` and ``states.csv`` agree.

The histogram: pixels of the box's central part (x from 20 % to 80 % of the width, y from
10 % to 90 % of the height, every second row and column) in HSV; a pixel with saturation
≥ 60 falls into one of 8 hues × 3 saturations, a grey one into one of 4 brightnesses
(:func:`box_histograms`, all boxes of a frame in one compiled pass).
"""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linear_sum_assignment

from mvtrack.config import RelinkSettings
from mvtrack.jit import kernel
from mvtrack.types import TrackFrame

Image = NDArray[np.uint8]
FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

HUES, SATS, GREYS = 8, 3, 4
#: bins of the appearance histogram
BINS = HUES * SATS + GREYS
#: saturation (0–255) from which a pixel counts by its hue
MIN_SATURATION = 60


def box_histograms(image: Image, tlwh: FloatArray, step: int = 2) -> FloatArray:
    """Normalised colour histograms (K, :data:`BINS`) of the central part of the boxes
    ``tlwh`` (K, 4) of a BGR ``image``, every ``step``-th row and column; all boxes at once.
    A box with no pixel in the image (or not a finite box) gets a row of zeros.

    The sampled pixels of every box are gathered into one row (:func:`sample_pixels`), turned
    to HSV by one ``cv2.cvtColor`` and counted into their boxes' bins (:func:`count_bins`)."""
    h_img, w_img = image.shape[:2]
    b = np.asarray(tlwh, np.float64).reshape(-1, 4)
    k = b.shape[0]
    if k == 0:
        return np.zeros((0, BINS))
    b = np.where(np.isfinite(b).all(axis=1, keepdims=True), b, 0.0)
    x0 = np.clip(b[:, 0] + 0.2 * b[:, 2], 0, w_img).astype(np.int64)
    x1 = np.clip(b[:, 0] + 0.8 * b[:, 2], 0, w_img).astype(np.int64)
    y0 = np.clip(b[:, 1] + 0.1 * b[:, 3], 0, h_img).astype(np.int64)
    y1 = np.clip(b[:, 1] + 0.9 * b[:, 3], 0, h_img).astype(np.int64)
    nx = np.maximum((x1 - x0 + step - 1) // step, 0)
    ny = np.maximum((y1 - y0 + step - 1) // step, 0)
    n = nx * ny  # sampled pixels per box
    hist = np.zeros((k, BINS))
    total = int(n.sum())
    if total == 0:
        return hist
    pixels = np.empty((1, total, 3), np.uint8)
    sample_pixels(np.ascontiguousarray(image), x0, x1, y0, y1, step, pixels[0])
    count_bins(cv2.cvtColor(pixels, cv2.COLOR_BGR2HSV)[0], n, hist)
    return hist


@kernel
def sample_pixels(image: Image, x0: IntArray, x1: IntArray, y0: IntArray, y1: IntArray,
                  step: int, out: Image) -> None:
    """The pixels ``image[y, x]`` of every box ``b`` at ``y`` in ``range(y0[b], y1[b], step)``
    and ``x`` in ``range(x0[b], x1[b], step)``, box after box, row after row, into ``out``
    (the total, 3)."""
    j = 0
    for b in range(x0.size):
        for y in range(y0[b], y1[b], step):
            for x in range(x0[b], x1[b], step):
                for c in range(3):
                    out[j, c] = image[y, x, c]
                j += 1


@kernel
def count_bins(hsv: Image, n: IntArray, hist: FloatArray) -> None:
    """Each box's ``n[b]`` pixels of ``hsv`` (OpenCV's 8-bit HSV, box after box) counted into
    its row of ``hist`` (zeros), normalised to a sum of 1: a pixel with saturation
    ≥ :data:`MIN_SATURATION` into one of :data:`HUES` × :data:`SATS` bins, a grey one into one
    of :data:`GREYS` brightnesses."""
    j = 0
    for b in range(n.size):
        for _ in range(n[b]):
            h, s, v = int(hsv[j, 0]), int(hsv[j, 1]), int(hsv[j, 2])
            if s >= MIN_SATURATION:
                hist[b, (h * HUES // 180) * SATS + s * SATS // 256] += 1.0
            else:
                hist[b, HUES * SATS + v * GREYS // 256] += 1.0
            j += 1
        if n[b] > 0:
            total = float(n[b])
            for i in range(BINS):
                hist[b, i] /= total


class Relinker:
    """Gives a new track the ID of a track that ended where and as it appears (module
    docstring); one call per frame, after the tracker's step.

    Parameters
    ----------
    fps : float
        Frame rate of the video (the window is in seconds).
    settings : RelinkSettings, optional
        The tests' thresholds.
    """

    def __init__(self, fps: float, settings: RelinkSettings | None = None) -> None:
        self.settings = RelinkSettings() if settings is None else settings
        self.fps = float(fps)
        self.window = max(1, round(self.settings.window * self.fps))
        self._ids = np.zeros(1, np.int64)  # tracker ID -> shown ID (0: not seen yet)
        self._app = np.zeros((1, BINS))  # tracker ID -> appearance
        self._has_app = np.zeros(1, bool)
        self._height = np.zeros(1)  # tracker ID -> box height, averaged like the appearance
        self._last = np.zeros((1, 7))  # tracker ID -> frame, x, y, vx, vy, w, h of last row
        # tracker ID -> frame, x, y of a row one to two seconds back, and of one up to a
        # second back (the mean velocity's start, and the next start)
        self._anchor = np.zeros((1, 3))
        self._mid = np.zeros((1, 3))
        self.span = max(1, round(float(fps)))  # frames: one second
        self._live = np.zeros(0, np.int64)  # tracker IDs shown in the previous frame
        # the gallery: tracker IDs of ended tracks, newest last
        self._ended = np.zeros(0, np.int64)
        #: (old shown ID, new tracker ID, frame) of every link made
        self.links: list[tuple[int, int, int]] = []

    def shown(self, ids: IntArray) -> IntArray:
        """The shown IDs of tracker IDs ``ids`` (IDs never seen map to themselves)."""
        ids = np.asarray(ids, np.int64)
        out = ids.copy()
        inside = (ids > 0) & (ids < self._ids.shape[0])
        mapped = self._ids[ids[inside]]
        out[inside] = np.where(mapped > 0, mapped, ids[inside])
        return out

    def __call__(self, image: Image, tracks: TrackFrame, live: IntArray | None = None
                 ) -> TrackFrame:
        """``tracks`` with their shown IDs; learns their appearance and ends.

        ``live`` are the tracker IDs still alive (coasting ones not output included), so
        that a track is ended only when the tracker deleted it; without it, a track is ended
        when it is no longer output.
        """
        pub = tracks.track_id > 0
        ids = tracks.track_id[pub]
        self._grow(int(ids.max()) + 1 if ids.size else 0)
        k = tracks.frame
        alive = ids if live is None else np.asarray(live, np.int64)
        gone = self._live  # the IDs of the last frame no longer alive (sorted, distinct)
        if gone.size and alive.size:
            seen = np.zeros(int(max(gone.max(), alive.max())) + 1, bool)
            seen[alive[alive > 0]] = True
            gone = gone[~seen[gone]]
        if gone.size:
            self._ended = np.concatenate([self._ended, gone])
        if self._ended.size:  # forget what ended too long ago
            self._ended = self._ended[k - self._last[self._ended, 0] <= self.window]
        self._live = np.unique(alive[alive > 0])
        new = ids[self._ids[ids] == 0]
        self._ids[new] = new
        rows = pub.nonzero()[0]
        measured = rows[tracks.det_index[rows] >= 0]
        if measured.size:
            self._learn(image, tracks, measured)
        now = np.column_stack([np.full(ids.size, float(k)), tracks.filtered_xy[pub]])
        born = np.isin(ids, new)
        self._anchor[ids[born]] = now[born]
        self._mid[ids[born]] = now[born]
        due = k - self._mid[ids, 0] >= self.span  # the mid row is a second old: shift
        if due.any():
            self._anchor[ids[due]] = self._mid[ids[due]]
            self._mid[ids[due]] = now[due]
        a = self._anchor[ids]
        dt = np.maximum(k - a[:, 0], 1.0)[:, None]
        v = np.where(k > a[:, [0]], (now[:, 1:] - a[:, 1:]) / dt, tracks.velocity[pub])
        self._last[ids] = np.column_stack([now, v, tracks.wh[pub]])
        if new.size and self._ended.size:
            self._link(new)
        return dataclasses.replace(tracks, track_id=self.shown(tracks.track_id))

    def _grow(self, n: int) -> None:
        if n <= self._ids.shape[0]:
            return
        m = max(n, 2 * self._ids.shape[0])
        self._ids = np.concatenate([self._ids, np.zeros(m - self._ids.shape[0], np.int64)])
        self._app = np.concatenate([self._app, np.zeros((m - self._app.shape[0], BINS))])
        self._has_app = np.concatenate([self._has_app, np.zeros(m - self._has_app.size, bool)])
        self._height = np.concatenate([self._height, np.zeros(m - self._height.size)])
        self._last = np.concatenate([self._last, np.zeros((m - self._last.shape[0], 7))])
        self._anchor = np.concatenate([self._anchor, np.zeros((m - self._anchor.shape[0], 3))])
        self._mid = np.concatenate([self._mid, np.zeros((m - self._mid.shape[0], 3))])

    def _learn(self, image: Image, tracks: TrackFrame, rows: NDArray[np.intp]) -> None:
        """The appearance of the measured rows, averaged into their tracks'."""
        xy, wh = tracks.filtered_xy[rows], tracks.wh[rows]
        hist = box_histograms(image, np.column_stack([xy - wh / 2, wh]))
        ids = tracks.track_id[rows]
        a = self.settings.smoothing
        old = self._app[ids]
        first = ~self._has_app[ids]
        self._app[ids] = np.where(first[:, None], hist, (1 - a) * old + a * hist)
        self._height[ids] = np.where(first, wh[:, 1], (1 - a) * self._height[ids] + a * wh[:, 1])
        self._has_app[ids] = True

    def _link(self, new: IntArray) -> None:
        """Pair the new tracks with the ended ones (module docstring)."""
        s = self.settings
        g = self._ended
        gl, nl = self._last[g], self._last[new]
        gap = nl[:, 0][:, None] - gl[:, 0][None, :]  # (new, ended) frames
        pred = gl[None, :, 1:3] + gl[None, :, 3:5] * gap[..., None]
        dist = np.linalg.norm(nl[:, None, 1:3] - pred, axis=2)
        # heights: the ended track's average over its measured rows (its last box shrinks as
        # it disappears behind the occluder), the new track's first box
        hn, hg = self._height[new][:, None], self._height[g][None, :]
        tall = np.maximum(hn, hg)
        radius = (s.reach + s.spread * gap / self.fps) * tall  # (ρ + σ Δk / f) max(h, h')
        ratio = tall / np.maximum(np.minimum(hn, hg), 1e-9)
        sim = np.sqrt(self._app[new][:, None, :] * self._app[g][None, :, :]).sum(axis=2)
        both = self._has_app[new][:, None] & self._has_app[g][None, :]
        ok = (gap > 0) & (dist <= radius) & (ratio <= s.size_ratio) & both & (
            sim >= s.min_similarity)
        if not ok.any():
            return
        cost = np.where(ok, dist / radius + (1.0 - sim), 1e6)
        r, c = linear_sum_assignment(cost)
        keep = ok[r, c]
        r, c = r[keep], c[keep]
        self._ids[new[r]] = self._ids[g[c]]
        self.links += [(int(self._ids[g[j]]), int(new[i]), int(nl[i, 0]))
                       for i, j in zip(r, c, strict=True)]
        self._ended = np.delete(g, c)
