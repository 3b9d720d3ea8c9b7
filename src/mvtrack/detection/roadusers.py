r"""The default video front end: any moving road user — cars, buses, people — from one model.

``RoadUserDetector(frame) -> Detections`` runs, frame by frame:

1. the background (:class:`~mvtrack.detection.colourbg.ColourBackground`: per-pixel colour
   mean and noise, a selective update that keeps a stopped object foreground without leaving
   a ghost when it drives on, shadows, ghosts, camera jitter), started from the temporal
   median of the first frames (read ahead, so objects in view from the first frame are not
   learnt into it);
2. a 3×3 opening and a small closing, and 8-connected blobs (``min_area``);
3. blobs into which several of the tracker's predicted boxes fall are divided among them
   (:func:`~mvtrack.detection.splitmerge.split_by_tracks`);
4. blobs longer than one object of the scene's kinds where they stand are cut at their waists,
   and fragments whose union is one object are joined (:mod:`mvtrack.detection.waists`);
5. boxes smaller than a share of every kind where they stand are clutter and dropped.

The kinds and their sizes at every image position (:class:`~mvtrack.detection.kinds.KindModel`)
are learnt from the scene itself: from its blobs, as found (not the boxes made of them, so
the model does not feed on its own decisions), each weighted by its area, so that clutter and
fragments weigh little; the kinds that hold a share of that weight are the scene's objects
(cars and the pairs of cars that merge in dense traffic on a highway; walkers on a campus).
Nothing assumes people or cars: until the model has its first samples, steps 4 and 5 wait.
The tracker's predicted boxes come back after each step (:meth:`RoadUserDetector.observe`).

Boxes come back in the input frame's pixels (the blob's bounding box, not a box around its
centroid); :attr:`RoadUserDetector.flags` says for each whether it is plain, merged or split;
:attr:`RoadUserDetector.mask` is the cleaned foreground at the input size, for the
stopped-object templates and for ``mvtrack track --masks``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.adaptive import temporal_median
from mvtrack.detection.background import box_cover
from mvtrack.detection.colourbg import ColourBackground
from mvtrack.detection.frameloop import (  # noqa: F401 (BOOTSTRAPS: public here too)
    BOOTSTRAPS,
    check_bootstrap,
    input_size_mask,
    read_ahead,
)
from mvtrack.detection.kinds import KindModel
from mvtrack.detection.labelling import label_blobs
from mvtrack.detection.splitmerge import (
    MERGED,
    PLAIN,
    SPLIT,
    blob_claims,
    split_by_tracks,
    usable_predictions,
)
from mvtrack.detection.travel import Travel
from mvtrack.detection.waists import cut_at_waists, join_fragments
from mvtrack.detection.wings import cut_flat_wings
from mvtrack.types import Detections, TrackFrame, TrackState, take_rows

Image = NDArray[np.uint8]
FloatArray = NDArray[np.float64]

#: a box with less than this share of the area of the commonest kind where it stands may be
#: a fragment of an object (a car broken at its windscreen), and is offered for joining
FRAGMENT = 0.8

#: frames of the read-ahead (evenly spaced) whose per-pixel median is the first background:
#: an object must cover a pixel in more than half of them to stay in it
BOOTSTRAP_MEDIAN = 9



class RoadUserDetector:
    """The road-user front end (module docstring), as the video frame loop runs it.

    Parameters
    ----------
    bootstrap : "start" or "none", default "start"
        Start the background from the temporal median of the first ``bootstrap_frames``
        frames (read ahead by :meth:`prepare`), or from the first frame.
    bootstrap_frames : int, default 20
    learn : bool, default True
        Learn the scene's kinds from its blobs.
    scale : float, default 1
        Working scale: the frame is reduced by it before modelling (``cv2.INTER_AREA``).
    min_area : float, default 40
        Smallest blob, working pixels (the video pipeline gives ``40 s²`` pixels of the
        frame, ``s² = W H / 320·240``: :data:`mvtrack.video.settings.ROAD_USERS_AREA`).
    close_size : int, default 5
        Diameter of the elliptic closing, working pixels (0 or 1: none), until the kinds are
        known.
    close_frac : float, default 0.2
        Then the closing is an ellipse this share of the smallest kind's width and height
        where each band of rows stands (0: ``close_size`` always). Chosen by leave-one-out
        over the four US-101 clips and KITTI-17 (every fold: docs/bench/vehicles.md).
    close_bands : int, default 8
        Bands of rows of the closing.
    over, min_part, valley : float, default 1.8, 0.5, 0.5
        Waist cutting (:func:`~mvtrack.detection.waists.cut_at_waists`); ``over`` and
        ``valley`` chosen by leave-one-out (4 and 3 folds of 5).
    small : float, default 0.35
        Boxes whose area is below this share of every kind's where they stand are dropped
        (chosen by leave-one-out end to end: every fold).
    max_z : float, default 3
        A part of a cut blob must be one object of some kind within this distance
        (:meth:`~mvtrack.detection.kinds.KindModel.match`), else the blob stays whole
        (leave-one-out: every fold).
    wings : float, default 0.3
        Flat wings at a blob's base (a cast shadow, walkers joined by their shadows) lower
        than this share of the blob's height are cut off
        (:func:`~mvtrack.detection.wings.cut_flat_wings`; leave-one-out end to end: 4 folds).
    travel : float, default 0.25
        Box sizes a track travels from where it was born before it is shown, held and learnt
        from (:class:`~mvtrack.detection.travel.Travel`; leave-one-out end to end: every fold).
    hold : bool, default True
        Keep the pixels inside the boxes the tracker predicts for its confirmed tracks out
        of the background's update (mean and noise), up to ``absorb_after`` frames: a car
        that waits does not fade from its faintest pixels inwards.
    alpha, alpha_slow, absorb_after, k_sigma, min_diff, jitter, shadows, ghost_every
        :class:`~mvtrack.detection.colourbg.ColourBackground` parameters (``absorb_after``
        and ``ghost_every`` in frames; the video pipeline sets them from the frame rate).

    Attributes
    ----------
    kinds : KindModel
        The scene's kinds, learnt from the blobs.
    flags : (M,) int8
        Plain / merged / split flag of each box of the last frame.
    """

    name = "road-users"

    def __init__(
        self,
        *,
        bootstrap: str = "start",
        bootstrap_frames: int = 20,
        learn: bool = True,
        scale: float = 1.0,
        min_area: float = 40.0,
        close_size: int = 5,
        over: float = 1.8,
        min_part: float = 0.5,
        valley: float = 0.5,
        small: float = 0.35,
        max_z: float = 3.0,
        close_frac: float = 0.2,
        close_bands: int = 8,
        wings: float = 0.3,
        travel: float = 0.25,
        hold: bool = True,
        alpha: float = 0.02,
        alpha_slow: float = 0.0,
        absorb_after: int = 600,
        k_sigma: float = 3.5,
        min_diff: float = 18.0,
        jitter: int = 1,
        shadows: bool = True,
        ghost_every: int = 10,
    ) -> None:
        check_bootstrap(bootstrap)
        if isinstance(bootstrap_frames, bool) or int(bootstrap_frames) < 1:
            raise ValueError(f"bootstrap_frames must be at least 1, got {bootstrap_frames}")
        if not (math.isfinite(scale) and 0.05 <= scale <= 1.0):
            raise ValueError(f"scale must be in [0.05, 1], got {scale}")
        if not (math.isfinite(min_area) and min_area >= 0):
            raise ValueError(f"min_area must be a number >= 0, got {min_area}")
        if isinstance(close_size, bool) or not isinstance(close_size, int) or close_size < 0:
            raise ValueError(f"close_size must be a whole number >= 0, got {close_size!r}")
        for name, value, lo, hi in (("over", over, 1.0, 10.0), ("min_part", min_part, 0.0, 1.0),
                                    ("valley", valley, 0.0, 1.0), ("small", small, 0.0, 1.0)):
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"{name} must be in [{lo:g}, {hi:g}], got {value}")
        self.background = ColourBackground(
            alpha=alpha, alpha_slow=alpha_slow, absorb_after=absorb_after, k_sigma=k_sigma,
            min_diff=min_diff, jitter=jitter, shadows=shadows, ghost_every=ghost_every)
        self.kinds = KindModel()
        # which of the tracker's tracks have travelled (by the tracker's IDs), and which of
        # the tracks shown have (by the IDs shown)
        self.travel = Travel(travel)
        self._shown = Travel(travel)
        #: the boxes the tracker predicts for the next frame of its confirmed tracks that
        #: have travelled (for blobs that several tracks share, and held)
        self.predicted: FloatArray | None = None
        self.learn_kinds = bool(learn)
        self.bootstrap = bootstrap
        self.bootstrap_frames = int(bootstrap_frames)
        self.scale = float(scale)
        self.min_area = float(min_area)
        self.close_size = int(close_size)
        self.over, self.min_part, self.valley = float(over), float(min_part), float(valley)
        self.small = float(small)
        self.max_z = float(max_z)
        self.hold = bool(hold)
        self.close_frac = float(close_frac)
        self.close_bands = int(close_bands)
        self.wings = float(wings)
        self._open = np.ones((3, 3), np.uint8)
        self._close = (None if close_size <= 1 else
                       cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (close_size, close_size)))
        self.frames_seen = 0
        self.flags = np.zeros(0, np.int8)
        self._mask: Image | None = None
        self._shape: tuple[int, int] | None = None

    # ------------------------------------------------------------------ geometry
    def reduce(self, frame: Image) -> Image:
        """``frame`` at the working scale."""
        if self.scale == 1.0:
            return frame
        h, w = frame.shape[:2]
        size = (max(round(w * self.scale), 1), max(round(h * self.scale), 1))
        return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)

    def to_work(self, tlwh: FloatArray) -> FloatArray:
        """Boxes in input pixels → working pixels (pixel centres on integers in both)."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4).copy()
        b[:, :2] = (b[:, :2] + 0.5) * self.scale - 0.5
        b[:, 2:] *= self.scale
        return b

    def to_input(self, tlwh: FloatArray) -> FloatArray:
        """Boxes in working pixels → input pixels."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4).copy()
        b[:, :2] = (b[:, :2] + 0.5) / self.scale - 0.5
        b[:, 2:] /= self.scale
        return b

    @property
    def mask(self) -> Image | None:
        """The cleaned foreground of the last frame (0/255) at the input frame's size."""
        return input_size_mask(self._mask, self._shape)

    # ------------------------------------------------------------------ the loop's hooks
    def prepare(self, frames: Iterable[Image]) -> Iterator[Image]:
        """``frames`` again, every one of them; with ``bootstrap="start"`` the first
        ``bootstrap_frames`` are read ahead (:func:`~mvtrack.detection.frameloop.read_ahead`:
        lazily, a read error after the frames read) and the background starts from the
        temporal median of up to :data:`BOOTSTRAP_MEDIAN` of them, evenly spaced."""
        count = 0 if self.bootstrap == "none" else self.bootstrap_frames
        yield from read_ahead(frames, count, self._bootstrap)

    def _bootstrap(self, head: list[Image]) -> None:
        self.background.bootstrap(
            temporal_median((self.reduce(f) for f in head), max_frames=BOOTSTRAP_MEDIAN))

    def observe(self, dets: Detections, tracks: TrackFrame) -> None:
        """After each tracker step: keep the boxes predicted for the next frame of the
        confirmed tracks that have travelled, and learn the kinds from their detections
        (blobs as found, isolated, off the border)."""
        size = None if self._shape is None else (self._shape[1], self._shape[0])
        moved = self.travel.update(tracks, size) & (tracks.state != int(TrackState.DELETED))
        xy = tracks.filtered_xy[moved] + tracks.velocity[moved]
        self.predicted = np.column_stack([xy - tracks.wh[moved] / 2, tracks.wh[moved]])
        if not self.learn_kinds or not moved.any() or len(dets) == 0:
            return
        rows = tracks.det_index[moved & (tracks.det_index >= 0)]
        if rows.size == 0 or len(self.flags) != len(dets):
            return
        boxes = dets.tlwh[rows]
        good = (self.flags[rows] == PLAIN) & ~self._at_border(boxes)
        if good.any():
            self.kinds.update(boxes[good])

    def shown(self, tracks: TrackFrame) -> TrackFrame:
        """The rows of ``tracks`` (IDs as shown) whose tracks have travelled: a track is shown
        from its first row ``travel`` box sizes from where it was born
        (:class:`~mvtrack.detection.travel.Travel`)."""
        size = None if self._shape is None else (self._shape[1], self._shape[0])
        keep = self._shown.update(tracks, size)
        if keep.all():
            return tracks
        return take_rows(tracks, keep)

    def reset(self) -> None:
        """Forget the background (the kinds are kept)."""
        self.background.reset()
        self.frames_seen = 0
        self._mask = None

    # ------------------------------------------------------------------ frames
    def __call__(self, frame: Image, index: int | None = None) -> Detections:
        """Detections of ``frame`` (BGR or grey ``uint8``); ``index``: its frame number."""
        if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
            raise ValueError(f"road-users: frame must be a uint8 image, got {frame.dtype} "
                             f"{frame.shape}")
        k = self.frames_seen if index is None else int(index)
        self.frames_seen += 1
        self._shape = frame.shape[:2]
        img = self.reduce(frame)
        held = None
        pred = self.predicted
        if self.hold and pred is not None and len(pred):
            held = box_cover(self.to_work(pred), img.shape[:2])
        raw = self.background.apply(img, held)
        if raw is None:
            self.flags = np.zeros(0, np.int8)
            self._mask = None
            return Detections.empty(k)
        mask = morph_around(raw, cv2.MORPH_OPEN, self._open)
        mask = self._closing(mask)
        self._mask = mask
        boxes, flags, area = self._objects(mask)
        self.flags = flags
        out = self.to_input(boxes)
        return Detections(k, out[:, :2] + out[:, 2:] / 2, out[:, 2:], None,
                          area / self.scale**2)

    def _closing(self, mask: Image) -> Image:
        """The closing: ``close_size`` until the kinds are known; then, in bands of rows, an
        ellipse ``close_frac`` of the smallest kind's size where the band stands (shaped
        like the objects: upright for walkers, wide for cars seen from the side)."""
        kinds = self.kinds
        if not kinds.ready or self.close_frac <= 0:
            if self._close is None:
                return mask
            return morph_around(mask, cv2.MORPH_CLOSE, self._close)
        h, w = mask.shape
        n = self.close_bands
        edges = np.linspace(0, h, n + 1).round().astype(int)
        bottoms = (edges[1:] - 0.5) / self.scale  # input rows
        probe = np.column_stack([np.full(n, self._shape[1] / 2.0 - 0.5), bottoms - 1.0,
                                 np.ones(n), np.ones(n)])
        size = kinds.expected(probe)[:, 0, :] * self.scale * self.close_frac
        ksize = np.clip(np.round(size).astype(int) | 1, 1, max(h, w) // 4 | 1)
        out = np.zeros_like(mask)
        b = 0
        while b < n:  # a few bands of rows, not objects; neighbours of one size at once
            kw, kh = int(ksize[b, 0]), int(ksize[b, 1])
            e = b + 1
            while e < n and ksize[e, 0] == kw and ksize[e, 1] == kh:
                e += 1
            y0, y1 = int(edges[b]), int(edges[e])
            b = e
            if kw <= 1 and kh <= 1:
                out[y0:y1] = mask[y0:y1]
                continue
            # a closing reaches 2 (kh // 2) <= kh rows: the rows around the band decide it
            a0, a1 = max(y0 - kh, 0), min(y1 + kh, h)
            kern = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (kw, kh))
            closed = morph_around(mask[a0:a1], cv2.MORPH_CLOSE, kern)
            out[y0:y1] = closed[y0 - a0 : y1 - a0]
        return out

    def _objects(self, mask: Image) -> tuple[FloatArray, NDArray[np.int8], FloatArray]:
        """Object boxes (working pixels), their flags and foreground areas (steps 3–5)."""
        labels, stats = label_blobs(mask)
        ids = np.flatnonzero(stats[:, cv2.CC_STAT_AREA] >= self.min_area)
        ids = ids[ids > 0]
        boxes, src, area = cut_flat_wings(labels, ids, stats, self.wings)
        big = area >= self.min_area
        boxes, ids, area = boxes[big], ids[src[big]], area[big]
        flags = np.full(len(boxes), PLAIN, np.int8)
        if len(boxes) == 0:
            return boxes, flags, area
        kinds = self.kinds
        pred = self.predicted
        pred = usable_predictions(None if pred is None else self.to_work(pred))
        # 3. blobs that two or more tracks predict into divided among them
        k_of = np.zeros(len(boxes), np.int64)
        if len(pred) >= 2:
            home, claims = blob_claims(boxes, pred, 0.5)
            k_of = np.bincount(home[claims], minlength=len(boxes))
        # 4. blobs longer than the smallest kind where they stand, cut at their waists
        long = np.zeros(len(boxes), bool)
        if kinds.ready:
            one = kinds.expected(self.to_input(boxes))[:, 0, :] * self.scale  # smallest kind
            long = (boxes[:, 2:] >= self.over * one).any(axis=1) & (k_of < 2)
        by_tracks = np.flatnonzero(k_of >= 2)
        if not long.any() and by_tracks.size == 0:
            return self._tidy(boxes, flags, area)
        rest = ~long & (k_of < 2)
        new_boxes, new_flags, new_area = [boxes[rest]], [flags[rest]], [area[rest]]
        for i in by_tracks.tolist():  # the few blobs shared by several tracks
            mine = np.flatnonzero(claims & (home == i))
            got = split_by_tracks(boxes[i], mask, pred[mine])
            new_boxes.append(got)
            new_flags.append(np.full(len(got), SPLIT, np.int8))
            new_area.append(got[:, 2] * got[:, 3] * area[i] / (boxes[i, 2] * boxes[i, 3]))
        if long.any():
            li = np.flatnonzero(long)
            got, src = cut_at_waists(labels, ids[li], boxes[li], one[li], over=self.over,
                                     min_part=self.min_part, valley=self.valley)
            cut = np.bincount(src, minlength=li.size) >= 2
            # a cut stands only if every part is one object of some kind where it stands,
            # and, if the blob itself is one object of a kind, the parts' kinds are commoner
            # (two cars side by side against a rarer kind of their size; a two-tone car
            # against a rarer kind of half-cars)
            kind_p, parts, z = kinds.match(self.to_input(got))
            one_p = (parts == 1).all(axis=1) & (z <= self.max_z)
            common = np.where(one_p, kinds.share[kind_p], 0.0)
            least = np.full(li.size, np.inf)
            np.minimum.at(least, src, common)
            kind_w, parts_w, z_w = kinds.match(self.to_input(boxes[li]))
            one_w = (parts_w == 1).all(axis=1) & (z_w <= self.max_z)
            bad = (np.bincount(src, ~one_p, minlength=li.size) > 0) | (
                one_w & (least <= kinds.share[kind_w]))
            undo = cut & bad
            if undo.any():
                got = np.concatenate([got[~undo[src]], boxes[li[undo]]])
                src = np.concatenate([src[~undo[src]], np.flatnonzero(undo)])
                cut &= ~undo
            new_boxes.append(got)
            new_flags.append(np.where(cut[src], SPLIT, PLAIN).astype(np.int8))
            fill = area[li] / (boxes[li, 2] * boxes[li, 3])
            new_area.append(got[:, 2] * got[:, 3] * fill[src])
        return self._tidy(np.concatenate(new_boxes), np.concatenate(new_flags),
                          np.concatenate(new_area))

    def _at_border(self, inp: FloatArray) -> NDArray[np.bool_]:
        """Boxes (input pixels) that touch the image's border: the object may be cut."""
        h, w = self._shape or (np.inf, np.inf)
        return (inp[:, 0] < 1.5) | (inp[:, 1] < 1.5) | (inp[:, 0] + inp[:, 2] > w - 2.5) | (
            inp[:, 1] + inp[:, 3] > h - 2.5)

    def _tidy(self, boxes: FloatArray, flags: NDArray[np.int8], area: FloatArray
              ) -> tuple[FloatArray, NDArray[np.int8], FloatArray]:
        """Join fragments among the plain boxes, drop clutter (steps 4 and 5)."""
        kinds = self.kinds
        if not kinds.ready or len(boxes) == 0:
            return boxes, flags, area
        inp = self.to_input(boxes)
        # each box's area as a share of each kind's where it stands
        share = (inp[:, None, 2] * inp[:, None, 3]) / kinds.expected(inp).prod(axis=2)
        # fragments are smaller than a whole object of the commonest kind: only they are
        # offered for joining
        common = int(np.argmax(kinds.share))
        part = np.flatnonzero((flags == PLAIN) & (share[:, common] < FRAGMENT))
        if part.size >= 2:
            joined, group = join_fragments(inp[part], kinds)
            if len(joined) < part.size:
                n_new = len(joined)
                counts = np.bincount(group, minlength=n_new)
                jarea = np.bincount(group, area[part], minlength=n_new)
                keep = np.setdiff1d(np.arange(len(boxes)), part)
                boxes = np.concatenate([self.to_work(joined), boxes[keep]])
                flags = np.concatenate([np.where(counts >= 2, MERGED, PLAIN).astype(np.int8),
                                        flags[keep]])
                area = np.concatenate([jarea, area[keep]])
                inp = self.to_input(boxes)
                share = (inp[:, None, 2] * inp[:, None, 3]) / kinds.expected(inp).prod(axis=2)
        # 5. clutter: smaller than `small` of every kind where it stands (not at the border),
        # or standing above the horizon
        ok = ((share.max(axis=1) >= self.small) | self._at_border(inp)) & kinds.standing(inp)
        return boxes[ok], flags[ok], area[ok]


def morph_around(mask: Image, op: int, kernel: Image) -> Image:
    """``cv2.morphologyEx(mask, op, kernel)`` for an opening or a closing, computed only over
    the bounding box of the foreground widened by the kernel's size on every side (clipped to
    the image).

    The same image: the first pass reaches at most half the kernel beyond the foreground
    and the second at most half the kernel further, and both treat the pixels beyond an edge
    of the window as the full image's pixels there are treated (all zero outside the widened
    box, where an erosion gives zero as well; the image's own border where the window meets
    it). The kernel must hold its centre (OpenCV's shapes do)."""
    if op not in (cv2.MORPH_OPEN, cv2.MORPH_CLOSE):
        raise ValueError(f"morph_around: an opening or a closing, got operation {op}")
    x, y, bw, bh = cv2.boundingRect(mask)
    out = np.zeros_like(mask)
    if bw == 0:
        return out
    h, w = mask.shape
    kh, kw = kernel.shape
    x0, x1 = max(x - kw, 0), min(x + bw + kw, w)
    y0, y1 = max(y - kh, 0), min(y + bh + kh, h)
    out[y0:y1, x0:x1] = cv2.morphologyEx(mask[y0:y1, x0:x1], op, kernel)
    return out
