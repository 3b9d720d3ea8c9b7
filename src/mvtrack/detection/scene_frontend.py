r"""The scene front end: per-pixel background, shadows, blobs, size prior, split and merge.

``SceneFrontEnd(frame, predicted=boxes) -> Detections`` runs, on a frame reduced to about
``work_pixels`` pixels (the model's cost follows the pixel count, and a person stays tens of
pixels tall):

1. the background model (:class:`~mvtrack.detection.adaptive.GaussianBackground`: per-pixel
   mean and variance, selective update with a slow path, shadows, ghosts, jitter);
2. a 3×3 opening and an elliptic closing whose diameter is ``close_frac`` of a typical object
   height from the size prior (``close_size`` until the prior has samples);
3. 8-connected blobs of at least ``min_area`` (working) pixels; each blob's box is trimmed to
   the columns holding at least ``trim`` of the blob's fullest column, which cuts the low
   horizontal tail of a cast shadow off a person's feet;
4. :func:`~mvtrack.detection.splitmerge.split_merge` with the tracker's predicted boxes and
   the size prior;
5. boxes no object of the scene could have (:meth:`SizePrior.plausible`) are dropped, and
   partial bodies are completed to the prior's height (:func:`complete_bodies`).

Boxes come back in the input frame's pixels; :attr:`SceneFrontEnd.flags` says for each
whether it is plain, merged or split. :func:`~mvtrack.detection.feedback.detect_with_tracker`
runs the front end and a :class:`~mvtrack.tracking.Tracker` together over a clip, feeding each
frame's predicted boxes back and teaching the size prior with the isolated confirmed tracks.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.adaptive import GaussianBackground, temporal_median
from mvtrack.detection.sizeprior import SizePrior
from mvtrack.detection.splitmerge import PLAIN, SPLIT, split_merge
from mvtrack.types import Detections

Image = NDArray[np.uint8]
FloatArray = NDArray[np.float64]


class SceneFrontEnd:
    """The default real-video front end (module docstring).

    Parameters
    ----------
    work_pixels : int, default 110_000
        Frames larger than this many pixels are reduced (``cv2.INTER_AREA``) by
        ``s = sqrt(work_pixels / (W H))`` before modelling; 0 keeps the full size.
    whole_factor : bool, default False
        Reduce by the whole factor ``n`` nearest to ``sqrt(W H / work_pixels)`` instead
        (``s = 1 / n``): several times faster to resize, but KITTI-17 MOTA 0.32 → 0.25 at
        ``s = 0.5`` instead of 0.493 (docs/bench/frontend.md: the figures move that much
        with small changes).
    background : GaussianBackground or None
        The background model (default: ``GaussianBackground()``).
    prior : SizePrior or None
        The size prior, in working pixels (default: ``SizePrior()``); shared with
        :func:`~mvtrack.detection.feedback.detect_with_tracker`, which teaches it.
    close_size : int, default 5
        Closing width (working pixels); people are upright, so the kernel is taller than wide.
    close_aspect : float, default 2
        Closing height over its width.
    close_frac : float, default 0.15
        Closing height as a fraction of the prior's median sample height, once it has
        samples (if larger).
    min_area : float, default 30
        Smallest blob, working pixels.
    trim : float, default 0.2
        Column share of step 3 (0 disables the trimming).
    split : bool, default True
        Run :func:`split_merge` (with the predicted boxes and the prior).
    reject : bool, default True
        Drop implausible boxes once the prior is ready.
    split_params : dict or None
        Keywords of :func:`~mvtrack.detection.splitmerge.split_merge` (``inside``,
        ``cover``, ``wide``, ``max_parts``).
    complete : float or None, default 0.85
        Boxes less than this share of the expected height at their foot row are completed
        upwards to it (:func:`complete_bodies`); None disables.
    verify : float or None, default None
        If set, a split box whose HOG people-detector margin
        (:func:`~mvtrack.detection.hog.hog_scores`, on the input frame) is below this value
        is dropped: the HOG detector as a verifier of split blobs only.

    Attributes
    ----------
    flags : (M,) int8
        Plain / merged / split flag of each box of the last call.
    mask : (h, w) uint8 or None
        The cleaned foreground mask of the last call, working size.
    scale : float
        The reduction factor ``s`` of the last frame.
    """

    name = "scene"

    def __init__(
        self,
        work_pixels: int = 110_000,
        background: GaussianBackground | None = None,
        prior: SizePrior | None = None,
        *,
        close_size: int = 5,
        close_aspect: float = 2.0,
        close_frac: float = 0.15,
        min_area: float = 30.0,
        trim: float = 0.2,
        split: bool = True,
        reject: bool = True,
        verify: float | None = None,
        split_params: dict[str, float] | None = None,
        complete: float | None = 0.85,
        whole_factor: bool = False,
    ) -> None:
        if work_pixels < 0:
            raise ValueError(f"work_pixels must be >= 0, got {work_pixels}")
        if not (0.0 <= trim < 1.0):
            raise ValueError(f"trim must be in [0, 1), got {trim}")
        if not (math.isfinite(min_area) and min_area >= 0):
            raise ValueError(f"min_area must be a non-negative number, got {min_area}")
        self.work_pixels = int(work_pixels)
        self.background = GaussianBackground() if background is None else background
        self.prior = SizePrior() if prior is None else prior
        self.close_size = int(close_size)
        self.close_frac = float(close_frac)
        self.close_aspect = float(close_aspect)
        self.min_area = float(min_area)
        self.trim = float(trim)
        self.split = bool(split)
        self.reject = bool(reject)
        self.verify = None if verify is None else float(verify)
        self.split_params = dict(split_params or {})
        self.complete = None if complete is None else float(complete)
        self.whole_factor = bool(whole_factor)
        self._hog: Any = None
        self.frames_seen = 0
        self.flags = np.zeros(0, np.int8)
        self.mask: Image | None = None
        self.scale = 1.0
        self._open = np.ones((3, 3), np.uint8)

    # ------------------------------------------------------------------ scale
    def _scale_for(self, shape: tuple[int, ...]) -> float:
        """``1 / n`` for the whole ``n`` nearest to ``sqrt(W H / work_pixels)`` (at least 1):
        an area reduction by a whole factor is several times faster than by any other."""
        h, w = shape[:2]
        if self.work_pixels == 0 or w * h <= self.work_pixels:
            return 1.0
        if self.whole_factor:
            return 1.0 / max(round(math.sqrt(w * h / self.work_pixels)), 1)
        return math.sqrt(self.work_pixels / (w * h))

    def reduce(self, frame: Image) -> Image:
        """``frame`` at the working size."""
        s = self._scale_for(frame.shape)
        self.scale = s
        if s == 1.0:
            return frame
        h, w = frame.shape[:2]
        size = (max(round(w * s), 1), max(round(h * s), 1))
        return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)

    def to_work(self, tlwh: FloatArray) -> FloatArray:
        """Boxes in input pixels → working pixels (pixel centres on integers in both)."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4).copy()
        s = self.scale
        b[:, :2] = (b[:, :2] + 0.5) * s - 0.5
        b[:, 2:] *= s
        return b

    def to_input(self, tlwh: FloatArray) -> FloatArray:
        """Boxes in working pixels → input pixels."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4).copy()
        s = self.scale
        b[:, :2] = (b[:, :2] + 0.5) / s - 0.5
        b[:, 2:] /= s
        return b

    # ------------------------------------------------------------------ model
    def bootstrap(self, frames: Iterable[Image], max_frames: int = 64) -> None:
        """Start the background from the temporal median of ``frames`` (e.g. the whole clip)."""
        self.background.bootstrap(
            temporal_median((self.reduce(f) for f in frames), max_frames=max_frames)
        )

    def reset(self, keep_prior: bool = True) -> None:
        """Forget the background (and the prior unless ``keep_prior``)."""
        self.background.reset()
        if not keep_prior:
            self.prior.reset()
        self.frames_seen = 0
        self.mask = None

    def learn(self, tlwh: FloatArray) -> None:
        """Teach the size prior boxes (input pixels) of isolated objects.

        Boxes that touch the left, right or top border are left out: the object may be cut
        by it. One cut by the bottom border is kept: its foot row is the last row, and a box
        standing there will be cut the same way.
        """
        b = self.to_work(tlwh)
        if self.mask is not None and len(b):
            w = self.mask.shape[1]
            inside = (b[:, 0] > 0.5) & (b[:, 1] > 0.5)
            inside &= b[:, 0] + b[:, 2] < w - 1.5
            b = b[inside]
        self.prior.update(b)

    def _closing(self) -> NDArray[np.uint8] | None:
        """Elliptic kernel ``close_size`` wide and ``close_aspect`` times as tall; once the
        prior has samples, ``close_frac`` of their median height tall if that is larger."""
        size = self.close_size
        tall = round(self.close_aspect * size)
        if self.prior.n_samples >= self.prior.min_samples:
            heights = self.prior._buf[: self.prior.n_samples, 2]
            tall = max(tall, round(self.close_frac * float(np.median(heights))))
        size, tall = max(size, 0) | 1, max(tall, 0) | 1
        if size <= 1 and tall <= 1:
            return None
        return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, tall))

    # ------------------------------------------------------------------ frames
    def __call__(
        self, frame: Image, index: int | None = None, predicted: FloatArray | None = None
    ) -> Detections:
        """Detections of ``frame``; ``predicted`` are the tracker's boxes (input pixels)."""
        k = self.frames_seen if index is None else int(index)
        self.frames_seen += 1
        img = self.reduce(frame)
        raw = self.background.apply(img)
        if raw is None:
            self.flags = np.zeros(0, np.int8)
            return Detections.empty(k)
        mask = cv2.morphologyEx(raw, cv2.MORPH_OPEN, self._open)
        close = self._closing()
        if close is not None:
            mask = cv2.morphologyEx(mask, cv2.MORPH_CLOSE, close)
        self.mask = mask
        boxes, area = self._blobs(mask)
        flags = np.full(len(boxes), PLAIN, np.int8)
        if self.split and len(boxes):
            pred = None if predicted is None else self.to_work(predicted)
            boxes, flags = split_merge(boxes, mask, pred, self.prior, **self.split_params)
            area = boxes[:, 2] * boxes[:, 3]
        if self.reject and len(boxes):
            ok = self.prior.plausible(boxes)
            boxes, flags, area = boxes[ok], flags[ok], area[ok]
        if self.complete is not None and self.prior.ready and len(boxes):
            boxes = complete_bodies(boxes, self.prior, self.complete)
        out = self.to_input(boxes)
        if self.verify is not None and (flags == SPLIT).any():
            from mvtrack.detection.hog import _hog, hog_scores

            self._hog = _hog() if self._hog is None else self._hog
            cand = np.flatnonzero(flags == SPLIT)
            ok = np.ones(len(out), bool)
            ok[cand] = hog_scores(frame, out[cand], self._hog) >= self.verify
            out, flags, area = out[ok], flags[ok], area[ok]
        self.flags = flags
        return Detections(k, out[:, :2] + out[:, 2:] / 2, out[:, 2:], None, area / self.scale**2)

    def _blobs(self, mask: Image) -> tuple[FloatArray, FloatArray]:
        """Boxes (tlwh, working pixels) and areas of the blobs, trimmed by column profile."""
        n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        keep = np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= self.min_area) + 1
        if keep.size == 0:
            return np.zeros((0, 4)), np.zeros(0)
        st = stats[keep].astype(np.float64)
        boxes = np.column_stack([st[:, 0] - 0.5, st[:, 1] - 0.5, st[:, 2], st[:, 3]])
        area = st[:, 4]
        if self.trim > 0:
            _h, w = mask.shape
            lab = labels[mask > 0]
            col = np.nonzero(mask)[1]
            counts = np.bincount(lab * w + col, minlength=n * w).reshape(n, w)[keep]
            full = counts >= self.trim * counts.max(axis=1, keepdims=True)
            first = full.argmax(axis=1)
            last = w - 1 - full[:, ::-1].argmax(axis=1)
            boxes[:, 0] = first - 0.5
            boxes[:, 2] = last - first + 1
        return boxes, area


def complete_bodies(boxes: FloatArray, prior: SizePrior, share: float = 0.85) -> FloatArray:
    """Boxes shorter than ``share`` of the expected height at their foot row, raised to it.

    The foot row is kept: feet on the ground stand out from it, while a head or shoulders
    against a wall of the same shade are the part that is lost (the usual partial body of
    a fixed camera looking down at people in front of buildings).
    """
    b = np.array(boxes, np.float64, copy=True).reshape(-1, 4)
    foot = b[:, 1] + b[:, 3]
    h_exp = prior.expected(foot)[:, 1]
    short = b[:, 3] < share * h_exp
    b[short, 3] = h_exp[short]
    b[short, 1] = foot[short] - h_exp[short]
    return b
