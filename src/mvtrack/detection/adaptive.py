r"""A per-pixel Gaussian background without ghosts: selective update, shadows, jitter, bootstrap.

The paper's disturbance map (:class:`~mvtrack.detection.background.DisturbanceMap`) learns its
running average everywhere and thresholds with one global :math:`T`; walkers then leave trails
that bridge neighbours, and a scene that starts with people in view keeps their ghosts. This
model keeps, per pixel ``p`` of a BGR frame :math:`I`,

.. math::

    \mu_k(p) \in \mathbb{R}^3, \qquad \sigma^2_k(p) \in \mathbb{R},

and calls ``p`` foreground when its colour distance to the background

.. math::

    d_k(p) = \max_c \,\min_{q \in N_j(p)} |I_{k,c}(p) - \mu_{k-1,c}(q)|  \qquad (1)

exceeds :math:`\max(\lambda \sigma_{k-1}(p), d_{\min})`. :math:`N_j(p)` is the
:math:`(2j+1)^2` neighbourhood of ``p`` (``jitter = j``): a pixel that matches the background
one pixel away is background, so a camera that shakes by a pixel does not light up every
edge (the neighbourhood model of Elgammal et al.); the minimum over the neighbourhood is
evaluated as the distance to the interval between the neighbourhood's per-channel minimum and
maximum (an erosion and a dilation of :math:`\mu`). Then the update is *selective*:

.. math::

    \mu_k = \mu_{k-1} + \alpha_p (I_k - \mu_{k-1}), \qquad
    \sigma^2_k = \sigma^2_{k-1} + \alpha_p (d_k^2 - \sigma^2_{k-1}), \qquad
    \alpha_p = \begin{cases} \alpha & p \text{ background} \\
                             \alpha_{\text{slow}} & p \text{ foreground} \end{cases}  \qquad (2)

(the variance only on background pixels, floored at :math:`\sigma_{\min}^2`). Foreground is
not learnt at the background's rate, so a walker leaves no trail. The slow path absorbs an
object that stays put, on purpose and whole: a pixel that has been foreground for
``absorb_after`` frames in a row is set to the frame (600 frames: a minute at 10 fps), while
:math:`\alpha_{\text{slow}} \ll \alpha` lets the model follow slow changes under it (and erodes
the object from its faintest pixels); the stopped-vehicle logic holds such an object
meanwhile.

Shadows (Cucchiara et al.'s test, here in normalised chromaticity): a foreground pixel whose
brightness ratio to the background lies in :math:`[r_{lo}, r_{hi}]` and whose chromaticity
:math:`(b, g, r) / (b + g + r)` differs from the background's by less than
:math:`\tau_c` (L1), or whose texture matches the background's, is a shadow and is not
foreground (:func:`~mvtrack.detection.shadows.shadow_mask`).

Ghosts — a background that holds an object which has since left — appear as foreground
blobs whose outline has strong edges in the background and none in the frame
(:func:`~mvtrack.detection.ghosts.ghost_blobs`); they are reset to the frame at once. A scene
that starts with objects in view is bootstrapped with the per-pixel temporal median of frames
spread over the start (online) or over the whole clip (offline, two passes;
:func:`temporal_median`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.ghosts import ghost_blobs, ghost_pixels
from mvtrack.detection.shadows import channel_max, channel_sum, shadow_mask

__all__ = [
    "GaussianBackground",
    "channel_max",
    "channel_sum",
    "ghost_blobs",
    "shadow_mask",
    "temporal_median",
]

Image = NDArray[np.uint8]


def temporal_median(frames: Iterable[Image], max_frames: int = 64) -> Image:
    """Per-pixel temporal median of ``frames`` (a bootstrap background), ``uint8``.

    Parameters
    ----------
    frames : iterable of (H, W, 3) or (H, W) uint8
        The frames to take the median of (all the same shape). Pass frames spread over the
        clip: a person who stands in less than half of them is gone from the median.
    max_frames : int, default 64
        At most this many frames are kept, evenly spaced over those given (memory: the
        median needs all of them at once).

    Raises
    ------
    ValueError
        No frames, or frames of different shapes.
    """
    stack = [np.asarray(f) for f in frames]
    if not stack:
        raise ValueError("temporal_median: no frames")
    shape = stack[0].shape
    if any(f.shape != shape for f in stack):
        raise ValueError("temporal_median: frames differ in shape")
    if len(stack) > max_frames:
        pick = np.linspace(0, len(stack) - 1, max_frames).round().astype(int)
        stack = [stack[i] for i in pick]
    if len(stack) > SORTED_MEDIAN or any(f.dtype != np.uint8 for f in stack):
        return np.median(np.stack(stack), axis=0).round().astype(np.uint8)
    return _sorted_median([np.array(f, np.uint8) for f in stack])


#: up to this many frames the median is taken by :func:`_sorted_median` (n² / 2 passes)
SORTED_MEDIAN = 16


def _sorted_median(frames: list[Image]) -> Image:
    """The per-pixel median of a few ``uint8`` images, as ``np.median(...).round()``: the
    images sorted pixel by pixel by an odd-even transposition network (``n`` rounds of
    compare-exchanges between neighbours, each a minimum and a maximum over whole images, no
    sort along a strided axis), then the middle one, or the mean of the two middle ones
    rounded half to even. Sorts ``frames`` in place."""
    n = len(frames)
    for r in range(n):  # a few frames, not pixels
        for i in range(r % 2, n - 1, 2):
            low = np.minimum(frames[i], frames[i + 1])
            np.maximum(frames[i], frames[i + 1], out=frames[i + 1])
            frames[i] = low
    if n % 2:
        return frames[n // 2]
    total = frames[n // 2 - 1].astype(np.uint16) + frames[n // 2]
    half, odd = total >> 1, total & 1
    return (half + (odd & half & 1)).astype(np.uint8)  # x.5 rounded to the even neighbour


def check_gaussian(alpha: float, alpha_slow: float, k_sigma: float, min_diff: float,
                   init_sigma: float, min_sigma: float) -> None:
    """Raise ``ValueError`` unless the parameters of a per-pixel Gaussian background
    (:class:`GaussianBackground`, :class:`~mvtrack.detection.colourbg.ColourBackground`) are
    valid: learning rates in ``[0, 1]`` with ``alpha_slow <= alpha``, a positive
    ``k_sigma``, ``min_diff`` in ``[0, 255)`` grey levels, ``0 < min_sigma <= init_sigma``."""
    for name, value in (("alpha", alpha), ("alpha_slow", alpha_slow)):
        if not (math.isfinite(value) and 0.0 <= value <= 1.0):
            raise ValueError(f"{name} must be in [0, 1], got {value}")
    if not alpha_slow <= alpha:
        raise ValueError(f"alpha_slow ({alpha_slow}) must not exceed alpha ({alpha})")
    if not (math.isfinite(k_sigma) and k_sigma > 0):
        raise ValueError(f"k_sigma must be a positive number, got {k_sigma}")
    if not (math.isfinite(min_diff) and 0 <= min_diff < 255):
        raise ValueError(f"min_diff must be in [0, 255) grey levels, got {min_diff}")
    if not (0 < min_sigma <= init_sigma):
        raise ValueError(f"need 0 < min_sigma <= init_sigma, got {min_sigma} and {init_sigma}")


def check_shadow_ratio(shadow_ratio: tuple[float, float]) -> tuple[float, float]:
    """``shadow_ratio`` as two floats ``(lo, hi)``; ``ValueError`` unless ``0 < lo < hi``."""
    lo, hi = shadow_ratio
    if not (0 < lo < hi):
        raise ValueError(f"shadow_ratio must be 0 < lo < hi, got {shadow_ratio}")
    return float(lo), float(hi)


class GaussianBackground:
    """Per-pixel mean and variance with a threshold in standard deviations (module docstring).

    Parameters
    ----------
    alpha : float, default 0.02
        Learning rate of background pixels, eq. (2) (a memory of about 50 frames).
    alpha_slow : float, default 0.0005
        Learning rate of foreground pixels, eq. (2). It erodes a parked object from its
        faintest pixels inward (on KITTI-17 half of a parked person's pixels are gone after
        about 30 s at 10 fps) and absorbs clutter that changed for good; 0 keeps an object
        whole until ``absorb_after``.
    absorb_after : int, default 600
        Consecutive foreground frames after which a pixel is absorbed (set to the frame): the
        slow path that takes a parked object into the background after a minute at 10 fps,
        not within seconds; 0 never.
    guard : bool, default False
        Learn at the slow rate also the pixels next to the foreground that differ from their
        own background but passed the neighbourhood test of eq. (1), so that an object does
        not erode from its outline inward while it waits to be absorbed (on by default it
        cost KITTI-17 MOTA 0.19 → 0.14, docs/bench/kitti.md).
    k_sigma : float, default 3.5
        :math:`\\lambda`, the threshold in standard deviations.
    min_diff : float, default 18
        :math:`d_{\\min}`, the smallest colour difference (grey levels, largest channel) that
        is foreground, whatever the variance (compression noise, flat regions).
    relative_floor : bool, default True
        Scale :math:`d_{\\min}` with the background's brightness,
        ``min_diff · clip(max_c μ_c / 128, 0.35, 1)``: in the shade an object shows less
        contrast (Weber's law).
    init_sigma : float, default 6
        Standard deviation of a freshly initialised background.
    min_sigma : float, default 2
        Floor of :math:`\\sigma`.
    jitter : int, default 1
        :math:`j` of eq. (1); 0 compares each pixel with its own background only.
    shadows : bool, default True
        Remove shadow pixels (:func:`~mvtrack.detection.shadows.shadow_mask`) from the
        foreground.
    shadow_ratio, shadow_chroma, shadow_texture
        ``ratio``, ``chroma`` and ``texture`` of :func:`~mvtrack.detection.shadows.shadow_mask`.
    ghost_every : int, default 10
        Test the foreground blobs for ghosts (:func:`~mvtrack.detection.ghosts.ghost_blobs`)
        every this many frames (0 never); a ghost's pixels are reset to the frame.

    Attributes
    ----------
    mean : (H, W, 3) float32 or None
        :math:`\\mu`; None until the first frame or :meth:`bootstrap`.
    var : (H, W) float32 or None
        :math:`\\sigma^2`.
    shadow : (H, W) uint8 or None
        The shadow pixels removed from the last mask (a reused buffer).
    """

    def __init__(
        self,
        alpha: float = 0.02,
        alpha_slow: float = 0.0005,
        absorb_after: int = 600,
        guard: bool = False,
        relative_floor: bool = True,
        k_sigma: float = 3.5,
        min_diff: float = 18.0,
        init_sigma: float = 6.0,
        min_sigma: float = 2.0,
        jitter: int = 1,
        shadows: bool = True,
        shadow_ratio: tuple[float, float] = (0.1, 1.3),
        shadow_chroma: float = 0.02,
        shadow_texture: float = 0.8,
        ghost_every: int = 10,
    ) -> None:
        check_gaussian(alpha, alpha_slow, k_sigma, min_diff, init_sigma, min_sigma)
        if absorb_after < 0:
            raise ValueError(f"absorb_after must be >= 0 frames, got {absorb_after}")
        if jitter < 0 or ghost_every < 0:
            raise ValueError(f"jitter and ghost_every must be >= 0, got {jitter}, {ghost_every}")
        lo, hi = check_shadow_ratio(shadow_ratio)
        self.alpha = float(alpha)
        self.alpha_slow = float(alpha_slow)
        self.absorb_after = int(absorb_after)
        self.guard = bool(guard)
        self.relative_floor = bool(relative_floor)
        self.k_sigma = float(k_sigma)
        self.min_diff = float(min_diff)
        self.init_sigma = float(init_sigma)
        self.min_sigma = float(min_sigma)
        self.jitter = int(jitter)
        self.shadows = bool(shadows)
        self.shadow_ratio = (lo, hi)
        self.shadow_chroma = float(shadow_chroma)
        self.shadow_texture = float(shadow_texture)
        self.ghost_every = int(ghost_every)
        self.reset()

    def reset(self) -> None:
        """Forget the model."""
        self.mean: NDArray[np.float32] | None = None
        self.var: NDArray[np.float32] | None = None
        self.shadow: Image | None = None
        self.run: NDArray[np.uint16] | None = None  # consecutive foreground frames
        self.frames_seen = 0
        self._kernel = (
            None if self.jitter == 0 else np.ones((2 * self.jitter + 1,) * 2, np.uint8)
        )

    def bootstrap(self, background: Image) -> None:
        """Start from a known background (e.g. :func:`temporal_median` of the clip)."""
        bg = _bgr(np.asarray(background))
        self.mean = bg.astype(np.float32)
        self.var = np.full(bg.shape[:2], self.init_sigma**2, np.float32)
        self.run = np.zeros(bg.shape[:2], np.uint16)

    def apply(self, frame: Image) -> Image | None:
        """Foreground of ``frame`` (0/255 ``uint8``), then the update of eq. (2).

        The first frame without a :meth:`bootstrap` initialises the model and returns None.
        """
        img = _bgr(frame)
        self.frames_seen += 1
        if self.mean is None or self.mean.shape != img.shape:
            self.bootstrap(img)
            return None
        f = img.astype(np.float32)
        mean = self.mean
        own = channel_max(cv2.absdiff(f, mean))  # distance to the pixel's own background
        if self._kernel is None:
            d = own
        else:  # eq. (1): distance to [min, max] of the neighbourhood, per channel
            lo = cv2.erode(mean, self._kernel)
            hi = cv2.dilate(mean, self._kernel)
            # max(lo − f, f − hi, 0) per channel, then the largest channel
            d = channel_max(cv2.max(cv2.max(cv2.subtract(lo, f), cv2.subtract(f, hi)), 0.0))
        floor = self.min_diff
        if self.relative_floor:  # Weber: a darker surface shows the same object with less
            # contrast, so the floor follows its brightness (down to a third of it)
            floor = self.min_diff * np.clip(channel_max(mean) / 128.0, 0.35, 1.0)
        thr = np.maximum(self.k_sigma * np.sqrt(self.var), floor)
        fg = d > thr
        mask = fg.astype(np.uint8) * np.uint8(255)
        if self.shadows:
            self.shadow = shadow_mask(
                f, mean, mask, self.shadow_ratio, self.shadow_chroma, self.shadow_texture,
                out=self.shadow,
            )
            mask[self.shadow > 0] = 0
        if self.ghost_every and self.frames_seen % self.ghost_every == 0:
            self._remove_ghosts(img, mask, f)
        # eq. (2): α_slow on the foreground and on the pixels next to it that the
        # neighbourhood test let pass although they differ from their own background
        # (learning those fast would let an object's colours spread into the background
        # from its outline inward), α elsewhere (shadows included)
        changed = mask > 0
        if self._kernel is not None and self.guard:
            near = cv2.dilate(mask, self._kernel) > 0
            changed |= near & (own > thr)
        if self.absorb_after:  # the slow path: changed for absorb_after frames is absorbed
            np.add(self.run, 1, out=self.run, where=changed & (self.run < 65535))
            self.run[~changed] = 0
            done = self.run >= self.absorb_after
            if done.any():
                mean[done] = f[done]
                self.run[done] = 0
        a = np.where(changed, np.float32(self.alpha_slow), np.float32(self.alpha))
        mean += a[..., None] * (f - mean)
        # the variance on every pixel left out of the mask, so that leaves and water, which
        # differ from their own mean often, widen their threshold
        still = mask == 0
        self.var[still] += self.alpha * (d[still] ** 2 - self.var[still])
        np.maximum(self.var, self.min_sigma**2, out=self.var)
        return mask

    def _remove_ghosts(self, img: Image, mask: Image, f: NDArray[np.float32]) -> None:
        if not mask.any():
            return
        grey = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        bg = cv2.cvtColor(self.mean.astype(np.uint8), cv2.COLOR_BGR2GRAY)
        sel = ghost_pixels(mask, grey, bg)
        if sel is None:
            return
        self.mean[sel] = f[sel]
        mask[sel] = 0


def _bgr(frame: Image) -> Image:
    if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
        raise ValueError(f"frame must be a uint8 image, got {frame.dtype} {frame.shape}")
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 1:
        return cv2.cvtColor(frame[:, :, 0], cv2.COLOR_GRAY2BGR)
    return frame
