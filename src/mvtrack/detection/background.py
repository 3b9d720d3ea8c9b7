"""Foreground models: paper 1's disturbance map, plain frame differencing, OpenCV's MOG2.

All three feed the same blob stage (:mod:`mvtrack.detection.blobs`) and share the
:class:`~mvtrack.detection.base.FrontEnd` interface, so the front ends can be compared on equal
terms (``mvtrack.detection.make_detector``).
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.base import FrontEnd, luminance
from mvtrack.detection.blobs import BlobExtractor
from mvtrack.jit import kernel
from mvtrack.types import Detections, TrackFrame


def _check_threshold(threshold: float) -> float:
    if not (math.isfinite(threshold) and 0 <= threshold < 255):
        raise ValueError(f"threshold must be in [0, 255) grey levels, got {threshold}")
    return float(threshold)


class DisturbanceMap(FrontEnd):
    r"""Paper 1's disturbance map (Halevi & Weinshall) over a running-average background.

    With luminance frames :math:`I_k` (SPEC §1.1, [R] defaults):

    .. math::

        D_k = I_k - B_{k-1}, \qquad
        B_k = (1 - \beta_k) B_{k-1} + \beta_k I_k, \qquad
        \beta_k = \max\!\left(\tfrac{1}{k+1}, \beta_{\min}\right), \qquad B_0 = I_0,

    and pixels with :math:`|D_k| > T` are foreground. :math:`B_k` is the true mean of
    :math:`I_0 \dots I_k` while :math:`1/(k+1) > \beta_{\min}`, then an exponential average with
    a memory of about :math:`1/\beta_{\min}` frames (50 at 0.02), so a vehicle that stops fades
    into the background and its blob vanishes, as paper 1 states (such tracks are held by
    :mod:`mvtrack.detection.template`). Frame 0 gives no detections (there is no
    :math:`B_{-1}`). The blob stage follows: 3×3 opening, 8-connected blobs, area ≥ 20 px.

    Parameters
    ----------
    threshold : float, default 25
        :math:`T` in grey levels (SPEC §1.1 [R]).
    beta_min : float, default 0.02
        Floor of the learning rate :math:`\beta_k` (SPEC §1.1 [R]).
    warmup : int, default 0
        Frames after a reset whose detections are suppressed.
    ghost_every : int, default 0
        Not in paper 1. Test the foreground blobs for ghosts every this many frames (0 never;
        :func:`~mvtrack.detection.ghosts.ghost_blobs`: an outline with the background's edges
        and not the frame's, the place a vehicle that stood long enough to be absorbed has
        left) and reset their pixels of :math:`B` to the frame, so the vehicle's track follows
        the vehicle, not the place it stood.
    hold : int, default 0
        Not in paper 1. Frames a pixel under a tracked object is kept out of :math:`B` (0: the
        paper's update everywhere). With ``hold > 0`` the video loop hands the tracker's
        output to :meth:`observe`, and the pixels inside the boxes the confirmed tracks are
        predicted at in the next frame are not learnt — a vehicle that stops in a queue stays
        foreground, and when it drives on the background under it is the road, not a ghost
        of it — until they have been held ``hold`` frames in a row; then they are learnt at
        the usual rate, so an object that parks is absorbed on purpose (the slow path).
    **blob
        The blob stage's keywords ``min_area, max_area, open_size, close_size, connectivity,
        center``, see :class:`~mvtrack.detection.blobs.BlobExtractor` (defaults 20, None, 3,
        0, 8, "centroid"). ``close_size`` (e.g. 7) merges fragments of one object.

    Notes
    -----
    The background is ``float32``; :math:`|D_k| > T` is evaluated on it exactly (no rounding of
    :math:`B`). One call costs a colour conversion, a widening pass (``accumulateWeighted``
    with weight 1), an ``absdiff``, a compare, one ``accumulateWeighted`` and the blob stage,
    all on preallocated buffers.
    """

    name = "disturbance-map"

    def __init__(
        self,
        threshold: float = 25.0,
        beta_min: float = 0.02,
        *,
        warmup: int = 0,
        ghost_every: int = 0,
        hold: int = 0,
        **blob: Any,
    ) -> None:
        if not (0.0 < beta_min <= 1.0):
            raise ValueError(f"beta_min must be in (0, 1], got {beta_min}")
        if isinstance(ghost_every, bool) or not isinstance(ghost_every, int) or ghost_every < 0:
            raise ValueError(f"ghost_every must be a whole number of frames >= 0, got "
                             f"{ghost_every!r}")
        super().__init__(BlobExtractor(**blob), warmup)
        self.threshold = _check_threshold(threshold)
        self.beta_min = float(beta_min)
        self.ghost_every = ghost_every
        if isinstance(hold, bool) or not isinstance(hold, int) or not 0 <= hold < 65535:
            raise ValueError(f"hold must be a whole number of frames in [0, 65534], got "
                             f"{hold!r}")
        self.hold = hold
        self._reset_model()

    def _reset_model(self) -> None:
        self.background: NDArray[np.float32] | None = None  #: B_k, float32 (H, W)
        self._k = 0
        self._grey: NDArray[np.uint8] | None = None
        self._grey_f: NDArray[np.float32] | None = None  # I_k, then |D_k|, float32
        self._fg: NDArray[np.uint8] | None = None
        self._thr: NDArray[np.float32] | None = None
        self._held_boxes = np.zeros((0, 4))  # tlwh of the tracks' boxes predicted for now
        self._held_for: NDArray[np.uint16] | None = None  # frames each pixel has been held
        self._cover = np.zeros((0, 0), np.uint8)  # the held boxes' pixels (hold_boxes)

    def beta(self, k: int) -> float:
        """Learning rate :math:`\\beta_k = \\max(1/(k+1), \\beta_{\\min})` (SPEC §1.1 [R])."""
        return max(1.0 / (k + 1), self.beta_min)

    def foreground(self, frame: NDArray[np.uint8]) -> NDArray[np.uint8] | None:
        """:math:`|I_k - B_{k-1}| > T` as a 0/255 mask, then :math:`B_k`; ``None`` at k = 0."""
        grey = luminance(frame, self._grey)
        if self.background is None or self.background.shape != grey.shape:
            self._grey = np.empty(grey.shape, np.uint8) if frame.ndim == 3 else None
            self.background = grey.astype(np.float32)  # B_0 = I_0 (SPEC §1.1 [R])
            # zero, so that the first widening below (0 · old + 1 · I) reads no garbage
            self._grey_f = np.zeros(grey.shape, np.float32)
            self._fg = np.empty(grey.shape, np.uint8)
            # T as a float32 image: cv2.compare against a scalar converts T to float32 as
            # well (same result), but takes about twice as long as against an array
            self._thr = np.full(grey.shape, self.threshold, np.float32)
            self._k = 0
            return None
        self._k += 1
        k = self._k
        d = self._grey_f
        # I_k widened to float32 in place: accumulateWeighted with weight 1 writes 0 · d + I_k,
        # exactly I_k (d holds finite grey levels), in one vectorised pass (np.copyto's
        # uint8 → float32 conversion takes about twice as long)
        cv2.accumulateWeighted(grey, d, 1.0)
        cv2.absdiff(d, self.background, dst=d)  # |D_k| = |I_k − B_{k−1}|
        if self._thr[0, 0] != np.float32(self.threshold):  # T changed since the reset
            self._thr.fill(self.threshold)
        cv2.compare(d, self._thr, cv2.CMP_GT, dst=self._fg)  # |D_k| > T
        if self.ghost_every and k % self.ghost_every == 0:
            self._remove_ghosts(grey)  # not in paper 1: ghosts reset to the frame there
        # B_k = (1 − β_k) B_{k−1} + β_k I_k, β_k = max(1/(k+1), β_min)  (SPEC §1.1 [R])
        if self.hold and len(self._held_boxes):  # not in paper 1: tracked pixels held
            cv2.accumulateWeighted(grey, self.background, self.beta(k),
                                   mask=self._learnt_pixels())
        else:
            if self._held_for is not None:
                self._held_for.fill(0)
            cv2.accumulateWeighted(grey, self.background, self.beta(k))
        return self._fg

    def observe(self, dets: Detections, tracks: TrackFrame, predicted: Any = None) -> None:
        """Keep the confirmed tracks' boxes predicted for the next frame (option ``hold``;
        the video loop calls this after each tracker step; ``predicted``: those boxes when
        the caller has them already, :func:`~mvtrack.detection.feedback.predicted_boxes`)."""
        if self.hold:
            if predicted is None:
                from mvtrack.detection.feedback import predicted_boxes

                predicted = predicted_boxes(tracks)
            self._held_boxes = predicted

    def _learnt_pixels(self) -> NDArray[np.uint8]:
        """The mask of the pixels :math:`B` learns this frame under ``hold``: those outside
        every held box, and those held ``hold`` frames in a row (the slow path); the count of
        the frames each pixel has been held is kept in one compiled pass
        (:func:`count_held`; with the boxes' cover in the same pass, :func:`hold_boxes`, when
        the boxes do not number over twice the image's pixels)."""
        shape = self._fg.shape
        if self._held_for is None or self._held_for.shape != shape:
            self._held_for = np.zeros(shape, np.uint16)
            self._cover = np.empty(shape, np.uint8)
        learnt = np.empty(shape, np.uint8)
        boxes = np.ascontiguousarray(self._held_boxes, np.float64).reshape(-1, 4)
        if not hold_boxes(boxes, self._cover, self._held_for, int(self.hold), learnt):
            count_held(box_cover(boxes, shape), self._held_for, int(self.hold), learnt)
        return learnt

    def _remove_ghosts(self, grey: NDArray[np.uint8]) -> None:
        """Reset the pixels of the ghost blobs of the raw mask to the frame (option
        ``ghost_every``); they leave the mask."""
        from mvtrack.detection.ghosts import reset_ghosts

        reset_ghosts(self._fg, grey, self.background)  # the edges of B_{k-1}


@kernel
def count_held(inside: NDArray[np.uint8], held: NDArray[np.uint16], hold: int,
               learnt: NDArray[np.uint8]) -> None:
    """Per pixel: ``held`` counts the frames in a row it lies ``inside`` a held box (0
    outside, at most ``hold + 1``); ``learnt`` is 255 where the background learns it, outside
    every box or held more than ``hold`` frames, else 0 (the count saturates at the
    ``uint16``'s 65 535)."""
    cap = min(hold + 1, 65535)
    for y in range(held.shape[0]):
        for x in range(held.shape[1]):
            if inside[y, x]:
                count = min(int(held[y, x]) + 1, cap)
                held[y, x] = count
                learnt[y, x] = 255 if count > hold else 0
            else:
                held[y, x] = 0
                learnt[y, x] = 255


def box_cover(tlwh: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray[np.uint8]:
    """The pixels of an image of ``shape`` (H, W) inside any of the boxes ``tlwh`` (K, 4), as
    a 0/255 mask. A box covers the pixels from ``floor(left)`` to ``ceil(left + width) - 1``,
    the same for rows. The boxes are filled in one compiled pass (:func:`fill_boxes`) when
    their pixels number at most twice the image's; else each box adds ±1 at its four corners
    of a difference image, whose 2-D prefix sum (``cv2.integral``) counts the boxes over each
    pixel."""
    h, w = shape[0], shape[1]
    b = np.asarray(tlwh, np.float64).reshape(-1, 4)
    ends = np.concatenate([np.floor(b[:, :2]), np.ceil(b[:, :2] + b[:, 2:])], axis=1)
    np.minimum(np.maximum(ends, 0.0, out=ends), (w, h, w, h), out=ends)
    x0, y0, x1, y1 = np.ascontiguousarray(ends.astype(np.intp).T)  # rows, one layout
    bw, bh = np.maximum(x1 - x0, 0), np.maximum(y1 - y0, 0)
    if int((bw * bh).sum()) <= 2 * h * w:  # pixels of the boxes: write them
        out = np.zeros((h, w), np.uint8)
        fill_boxes(out, x0, y0, x1, y1)
        return out
    corners = np.concatenate([y0 * (w + 1) + x0, y0 * (w + 1) + x1, y1 * (w + 1) + x0,
                              y1 * (w + 1) + x1])
    sign = np.repeat(np.array([1.0, -1.0, -1.0, 1.0]), len(b))
    diff = np.bincount(corners, sign, minlength=(h + 1) * (w + 1)).astype(np.float32)
    count = cv2.integral(diff.reshape(h + 1, w + 1), sdepth=cv2.CV_32F)[1 : h + 1, 1 : w + 1]
    return cv2.compare(count, 0.5, cv2.CMP_GT)


@kernel
def fill_boxes(out: NDArray[np.uint8], x0: NDArray[np.intp], y0: NDArray[np.intp],
               x1: NDArray[np.intp], y1: NDArray[np.intp]) -> None:
    """Set ``out[y0[k]:y1[k], x0[k]:x1[k]]`` to 255 for every box ``k`` (ends within the
    image)."""
    for k in range(x0.size):
        for y in range(y0[k], y1[k]):
            for x in range(x0[k], x1[k]):
                out[y, x] = 255


@kernel
def hold_boxes(tlwh: NDArray[np.float64], cover: NDArray[np.uint8], held: NDArray[np.uint16],
               hold: int, learnt: NDArray[np.uint8]) -> bool:
    """:func:`count_held` of :func:`box_cover` ``(tlwh, held.shape)`` in one compiled pass:
    ``cover`` (scratch, the shape of ``held``) gets the boxes' pixels, then ``held`` and
    ``learnt`` their counts. Returns False, and writes nothing, when the boxes' pixels number
    over twice the image's (:func:`box_cover` takes prefix sums there); a box with a NaN
    side covers nothing."""
    h, w = held.shape
    k = tlwh.shape[0]
    ends = np.zeros((k, 4), np.intp)
    total = 0
    for i in range(k):
        x0, y0 = np.floor(tlwh[i, 0]), np.floor(tlwh[i, 1])
        x1, y1 = np.ceil(tlwh[i, 0] + tlwh[i, 2]), np.ceil(tlwh[i, 1] + tlwh[i, 3])
        if np.isnan(x0) or np.isnan(y0) or np.isnan(x1) or np.isnan(y1):
            continue
        x0, x1 = min(max(x0, 0.0), float(w)), min(max(x1, 0.0), float(w))
        y0, y1 = min(max(y0, 0.0), float(h)), min(max(y1, 0.0), float(h))
        ends[i, 0], ends[i, 1], ends[i, 2], ends[i, 3] = int(x0), int(y0), int(x1), int(y1)
        total += max(int(x1) - int(x0), 0) * max(int(y1) - int(y0), 0)
    if total > 2 * h * w:
        return False
    cover[:, :] = 0
    for i in range(k):
        for y in range(ends[i, 1], ends[i, 3]):
            for x in range(ends[i, 0], ends[i, 2]):
                cover[y, x] = 255
    count_held(cover, held, hold, learnt)
    return True


class FrameDifference(FrontEnd):
    r"""Plain frame differencing, the baseline paper 1 rejects: :math:`|I_k - I_{k-1}| > T`.

    Paper 1 found it noise-sensitive and weakly linked in time (SPEC §1.1, step 2): a uniform
    object's interior cancels, and its leading and trailing edges give two blobs. Same blob
    stage and parameters as :class:`DisturbanceMap`.
    """

    name = "frame-diff"

    def __init__(
        self,
        threshold: float = 25.0,
        *,
        warmup: int = 0,
        **blob: Any,
    ) -> None:
        super().__init__(BlobExtractor(**blob), warmup)
        self.threshold = _check_threshold(threshold)
        self._reset_model()

    def _reset_model(self) -> None:
        self._prev: NDArray[np.uint8] | None = None
        self._cur: NDArray[np.uint8] | None = None
        self._absd: NDArray[np.uint8] | None = None
        self._fg: NDArray[np.uint8] | None = None

    def foreground(self, frame: NDArray[np.uint8]) -> NDArray[np.uint8] | None:
        """:math:`|I_k - I_{k-1}| > T` as a 0/255 mask; ``None`` for the first frame."""
        if self._prev is None or self._prev.shape != frame.shape[:2]:
            self._prev = luminance(frame).copy()
            self._cur = np.empty_like(self._prev)
            self._absd = np.empty_like(self._prev)
            self._fg = np.empty_like(self._prev)
            return None
        cur = luminance(frame, self._cur if frame.ndim == 3 else None)
        cv2.absdiff(cur, self._prev, dst=self._absd)
        cv2.compare(self._absd, self.threshold, cv2.CMP_GT, dst=self._fg)
        if cur is self._cur:
            self._prev, self._cur = self._cur, self._prev
        else:
            np.copyto(self._prev, cur)
        return self._fg


class _Subtractor(FrontEnd):
    """An OpenCV background subtractor (MOG2, KNN) as a front end: shadow pixels (marked 127
    by OpenCV when ``detect_shadows``) count as background; only confident foreground (255)
    goes to the blob stage. Subclasses build the model (:meth:`_create`)."""

    def __init__(
        self, history: int, threshold: tuple[str, float], detect_shadows: bool,
        learning_rate: float, use_color: bool, warmup: int, blob: dict[str, Any],
    ) -> None:
        name, value = threshold
        if history < 1:
            raise ValueError(f"history must be ≥ 1 frame, got {history}")
        if not value > 0:
            raise ValueError(f"{name} must be positive, got {value}")
        super().__init__(BlobExtractor(**blob), warmup)
        self.history = int(history)
        setattr(self, name, float(value))
        self.detect_shadows = bool(detect_shadows)
        self.learning_rate = float(learning_rate)
        self.use_color = bool(use_color)
        self._reset_model()

    def _create(self) -> Any:
        raise NotImplementedError

    def _reset_model(self) -> None:
        self._model = self._create()
        self._fg: NDArray[np.uint8] | None = None

    def foreground(self, frame: NDArray[np.uint8]) -> NDArray[np.uint8]:
        """The subtractor's mask with shadows (127) removed: 255 where foreground."""
        img = frame if self.use_color else luminance(frame)
        raw = self._model.apply(img, learningRate=self.learning_rate)
        if self._fg is None or self._fg.shape != raw.shape:
            self._fg = np.empty_like(raw)
        cv2.compare(raw, 127, cv2.CMP_GT, dst=self._fg)
        return self._fg


class MOG2(_Subtractor):
    """OpenCV's Gaussian-mixture background subtractor (``cv2.createBackgroundSubtractorMOG2``).

    Shadow pixels (marked 127 by OpenCV when ``detect_shadows``) are treated as background;
    only confident foreground (255) goes to the blob stage.

    Parameters
    ----------
    history : int, default 500
        Frames of history of the mixture model (OpenCV's default).
    var_threshold : float, default 16
        Squared Mahalanobis distance deciding whether a pixel fits the model (OpenCV's default).
    detect_shadows : bool, default True
        Mark and discard shadows.
    learning_rate : float, default -1
        OpenCV's learning rate; negative chooses it from ``history``.
    use_color : bool, default True
        Model the BGR frame (True) or its luminance (False).
    warmup, **blob
        As in :class:`DisturbanceMap`.
    """

    name = "mog2"

    def __init__(
        self,
        history: int = 500,
        var_threshold: float = 16.0,
        detect_shadows: bool = True,
        learning_rate: float = -1.0,
        use_color: bool = True,
        *,
        warmup: int = 0,
        **blob: Any,
    ) -> None:
        super().__init__(history, ("var_threshold", var_threshold), detect_shadows,
                         learning_rate, use_color, warmup, blob)

    def _create(self) -> Any:
        return cv2.createBackgroundSubtractorMOG2(
            history=self.history, varThreshold=self.var_threshold,
            detectShadows=self.detect_shadows,
        )


class KNN(_Subtractor):
    """OpenCV's k-nearest-neighbours background subtractor
    (``cv2.createBackgroundSubtractorKNN``), shadows discarded as in :class:`MOG2`.

    Parameters
    ----------
    history : int, default 500
        Frames of history (OpenCV's default).
    dist2_threshold : float, default 400
        Squared distance to a sample under which a pixel counts as close to it (OpenCV's
        default).
    detect_shadows, learning_rate, use_color, warmup, **blob
        As in :class:`MOG2` (the same defaults).
    """

    name = "knn"

    def __init__(
        self,
        history: int = 500,
        dist2_threshold: float = 400.0,
        detect_shadows: bool = True,
        learning_rate: float = -1.0,
        use_color: bool = True,
        *,
        warmup: int = 0,
        **blob: Any,
    ) -> None:
        super().__init__(history, ("dist2_threshold", dist2_threshold), detect_shadows,
                         learning_rate, use_color, warmup, blob)

    def _create(self) -> Any:
        return cv2.createBackgroundSubtractorKNN(
            history=self.history, dist2Threshold=self.dist2_threshold,
            detectShadows=self.detect_shadows,
        )
