r"""A per-pixel colour background in a few OpenCV passes a frame: the road-user front end's model.

:class:`ColourBackground` keeps, per pixel ``p`` of the working frame, a colour mean
:math:`\mu(p)` and a noise level :math:`\sigma(p)`, and calls ``p`` foreground when the
distance of the frame :math:`I` to the background,

.. math::

    d(p) = \max_c \max\big(\check\mu_c(p) - I_c(p),\; I_c(p) - \hat\mu_c(p),\; 0\big)  \qquad (1)

with :math:`\check\mu, \hat\mu` the minimum and maximum of :math:`\mu` over the
:math:`(2j+1)^2` neighbourhood of ``p`` (``jitter = j``: a pixel that matches the
background one pixel away is background, so a camera that shakes by a pixel does not light
up every edge), exceeds

.. math::

    \theta(p) = \max\big(\lambda\,\sigma(p),\; d_{\min} \cdot
                 \mathrm{clip}(\max_c \mu_c(p) / 128,\; 0.35,\; 1)\big),   \qquad (2)

the noise threshold or a floor that follows the background's brightness (in the shade an
object shows less contrast). The update is *selective*:

.. math::

    \mu \leftarrow \mu + \alpha_p (I - \mu), \qquad
    \sigma^2 \leftarrow \sigma^2 + \alpha (d^2 - \sigma^2) \text{ on background pixels not held},
    \qquad \alpha_p = \begin{cases} \alpha & \text{background} \\
                                     \alpha_{\text{slow}} & \text{foreground} \\
                                     0 & \text{held} \end{cases}   \qquad (3)

so an object that stops (a car at a red light) stays foreground and leaves the road behind it
when it drives on: no ghost. A pixel foreground for ``absorb_after`` frames in a row is
absorbed whole (set to the frame): an object that parks becomes background on purpose. Pixels
the caller *holds* (the boxes of tracked objects) are not learnt at all, for up to
``absorb_after`` frames.

Ghosts — a background that holds an object which has since left, e.g. a car that stood in the
bootstrap frames — are foreground blobs whose outline has the background's edges and not the
frame's (:func:`~mvtrack.detection.ghosts.ghost_pixels`); every ``ghost_every`` frames their
pixels are reset to the frame.

Shadows (``shadows=True``, Cucchiara et al.'s test with a texture test): a candidate pixel
darker than the background in every channel, with a brightness ratio in ``shadow_ratio``, is
a shadow when either its colour is kept (chromaticities within ``shadow_chroma``) and it adds
no texture of its own (its 3×3 grey-level spread at most the background's, scaled by the
ratio, plus ``shadow_texture``: a dark grey car on a grey road keeps the road's colour but
brings its own edges), or the background's texture is kept under a change of colour (a
shadow lit by the blue sky: the 3×3 correlation of frame and background above
``shadow_correlation`` on a background with texture). The test runs on the candidates only
(one compiled pass over them, :func:`shadow_cells`), not on the whole frame.

Cost: the mean, its neighbourhood extremes and the threshold map of eq. (2) are refreshed every
``refresh`` frames (they change at the rate α), and so are the noise and the count of frames a
pixel has been busy (a pixel is absorbed within ``refresh`` frames of ``absorb_after``); every
frame costs two saturated subtractions, two channel maxima, one compare and the masked update
of the mean — all ``uint8`` or one-channel passes but the last.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

from mvtrack.detection.adaptive import check_gaussian, check_shadow_ratio
from mvtrack.jit import kernel

Image = NDArray[np.uint8]

#: a blob is a ghost when its outline's edges in the background are this many times its
#: edges in the frame (:func:`~mvtrack.detection.ghosts.ghost_blobs`)
GHOST_RATIO = 2.0


_ROW3 = np.ones((1, 3), np.uint8)


def _channel_max(img: Image) -> Image:
    """Largest of the three channels per pixel: the interleaved row ``b g r b g r ...``
    dilated by a 1×3 window anchored at its left end holds each pixel's maximum at the
    pixel's first channel (one pass and a strided copy, about twice as fast as splitting the
    channels)."""
    h, w = img.shape[:2]
    row = cv2.dilate(img.reshape(h, 3 * w), _ROW3, anchor=(0, 0),
                     borderType=cv2.BORDER_REPLICATE)
    return np.ascontiguousarray(row[:, ::3])


class ColourBackground:
    """Per-pixel colour mean and noise with a selective update (module docstring).

    Parameters
    ----------
    alpha : float, default 0.02
        Learning rate of background pixels, eq. (3) (a memory of about 50 frames).
    alpha_slow : float, default 0
        Learning rate of foreground pixels, eq. (3); 0 keeps an object whole until it is
        absorbed.
    absorb_after : int, default 600
        Consecutive foreground (or held) frames after which a pixel is absorbed; 0 never.
    k_sigma : float, default 3.5
        :math:`\\lambda` of eq. (2).
    min_diff : float, default 18
        :math:`d_{\\min}` of eq. (2), grey levels of the largest channel.
    init_sigma, min_sigma : float, default 6 and 2
        Noise of a fresh background, and its floor.
    jitter : int, default 1
        :math:`j` of eq. (1); 0 compares each pixel with its own background only.
    shadows : bool, default True
        Leave shadow pixels out of the foreground.
    shadow_ratio : (float, float), default (0.2, 0.95)
        Brightness ratios frame / background a shadow may have.
    shadow_chroma : float, default 0.03
        Largest L1 distance of the chromaticities ``(b, g, r) / (b + g + r)``.
    shadow_texture : float, default 2
        Grey levels of local spread a shadow of the background's colour may add to the
        background's.
    shadow_correlation, shadow_min_texture : float, default 0.8 and 3
        A candidate whose colour changed is a shadow when the frame's grey levels correlate
        with the background's over a 3×3 window by more than ``shadow_correlation`` and the
        background has a local spread of at least ``shadow_min_texture`` grey levels.
    shadow_step : int, default 2
        The shadow test runs on every ``shadow_step``-th candidate of each row and column,
        each tested pixel deciding for its cell (a shadow is a region, not a pixel).
    ghost_every : int, default 10
        Frames between ghost tests (0 never).
    refresh : int, default 8
        Frames between refreshes of the threshold map and the neighbourhood extremes, and
        between updates of the noise and of the count that absorbs a pixel.

    Attributes
    ----------
    mean : (H, W, 3) float32 or None
        :math:`\\mu`.
    var : (H, W) float32 or None
        :math:`\\sigma^2`.
    distance : (H, W) uint8 or None
        :math:`d` of eq. (1) for the last frame (a reused buffer).
    """

    def __init__(
        self,
        alpha: float = 0.02,
        alpha_slow: float = 0.0,
        absorb_after: int = 600,
        k_sigma: float = 3.5,
        min_diff: float = 18.0,
        init_sigma: float = 6.0,
        min_sigma: float = 2.0,
        jitter: int = 1,
        shadows: bool = True,
        shadow_ratio: tuple[float, float] = (0.2, 0.95),
        shadow_chroma: float = 0.03,
        shadow_texture: float = 2.0,
        shadow_correlation: float = 0.8,
        shadow_min_texture: float = 3.0,
        shadow_step: int = 2,
        ghost_every: int = 10,
        refresh: int = 8,
    ) -> None:
        check_gaussian(alpha, alpha_slow, k_sigma, min_diff, init_sigma, min_sigma)
        for name, value in (("absorb_after", absorb_after), ("jitter", jitter),
                            ("ghost_every", ghost_every)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ValueError(f"{name} must be a whole number >= 0, got {value!r}")
        if isinstance(refresh, bool) or not isinstance(refresh, int) or refresh < 1:
            raise ValueError(f"refresh must be a whole number >= 1, got {refresh!r}")
        lo, hi = check_shadow_ratio(shadow_ratio)
        self.alpha = float(alpha)
        self.alpha_slow = float(alpha_slow)
        self.absorb_after = min(int(absorb_after), 65534)
        self.k_sigma = float(k_sigma)
        self.min_diff = float(min_diff)
        self.init_sigma = float(init_sigma)
        self.min_sigma = float(min_sigma)
        self.jitter = int(jitter)
        self.shadows = bool(shadows)
        self.shadow_ratio = (lo, hi)
        self.shadow_chroma = float(shadow_chroma)
        self.shadow_texture = float(shadow_texture)
        self.shadow_correlation = float(shadow_correlation)
        self.shadow_min_texture = float(shadow_min_texture)
        if isinstance(shadow_step, bool) or not isinstance(shadow_step, int) or shadow_step < 1:
            raise ValueError(f"shadow_step must be a whole number >= 1, got {shadow_step!r}")
        self.shadow_step = int(shadow_step)
        self.ghost_every = int(ghost_every)
        self.refresh = int(refresh)
        self._alpha_refresh = 1.0 - (1.0 - self.alpha) ** self.refresh
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget the model."""
        self.mean: NDArray[np.float32] | None = None
        self.var: NDArray[np.float32] | None = None
        self.distance: Image | None = None
        self.frames_seen = 0
        self._kernel = (None if self.jitter == 0
                        else np.ones((2 * self.jitter + 1,) * 2, np.uint8))
        level = np.arange(256, dtype=np.float64)  # eq. (2)'s floor of each brightness
        self._floor_table = np.floor(self.min_diff * np.clip(level / 128.0, 0.35, 1.0)).astype(
            np.uint8)
        self._stale = True

    def bootstrap(self, background: Image) -> None:
        """Start from a known background (e.g. the temporal median of the first frames)."""
        bg = _bgr(np.asarray(background))
        h, w = bg.shape[:2]
        self.mean = bg.astype(np.float32)
        self.var = np.full((h, w), self.init_sigma**2, np.float32)
        self._run = np.zeros((h, w), np.uint16)  # consecutive frames foreground or held
        self._d = np.empty((h, w), np.uint8)
        self._fg = np.empty((h, w), np.uint8)
        self._d32 = np.empty((h, w), np.float32)
        self._stale = True

    def _refresh(self) -> None:
        """The background as ``uint8``, its neighbourhood extremes and the threshold of
        eq. (2) as ``uint8`` (the noise term rounded, the floor read from a table of the
        256 brightnesses)."""
        self._mu8 = cv2.convertScaleAbs(self.mean)
        if self._kernel is None:
            self._lo = self._hi = self._mu8
        else:
            self._lo = cv2.erode(self._mu8, self._kernel)
            self._hi = cv2.dilate(self._mu8, self._kernel)
        np.maximum(self.var, np.float32(self.min_sigma**2), out=self.var)
        noise = cv2.convertScaleAbs(cv2.sqrt(self.var), alpha=self.k_sigma)  # λ σ
        floor = cv2.LUT(_channel_max(self._mu8), self._floor_table)
        self._thr = cv2.min(cv2.max(noise, floor), 254.0)
        if self.shadows:  # the grey background, padded by one pixel, for shadows
            self._mu_grey = cv2.cvtColor(self._mu8, cv2.COLOR_BGR2GRAY)
            self._mu_grey_pad = cv2.copyMakeBorder(self._mu_grey, 1, 1, 1, 1,
                                                   cv2.BORDER_REPLICATE)
        self._stale = False

    # ------------------------------------------------------------------ frames
    def apply(self, frame: Image, held: Image | None = None) -> Image | None:
        """Foreground of ``frame`` (0/255 ``uint8``, a reused buffer), then the update.

        Parameters
        ----------
        frame : (H, W, 3) or (H, W) uint8
            The working frame.
        held : (H, W) uint8, optional
            Pixels not to learn this frame (non-zero), e.g. inside the boxes of tracked
            objects; held for ``absorb_after`` frames in a row they are absorbed as well.

        Returns
        -------
        (H, W) uint8 or None
            None for the first frame without a :meth:`bootstrap` (it becomes the background).
        """
        img = _bgr(frame)
        self.frames_seen += 1
        if self.mean is None or self.mean.shape != img.shape:
            self.bootstrap(img)
            return None
        if self._stale or self.frames_seen % self.refresh == 0:
            self._refresh()
        up = cv2.subtract(img, self._hi)  # brighter than the neighbourhood, per channel
        d3 = cv2.max(cv2.subtract(self._lo, img), up)  # eq. (1)
        d = self._d = _channel_max(d3)
        fg = cv2.compare(d, self._thr, cv2.CMP_GT, dst=self._fg)  # eq. (2)
        self.distance = d
        if self.shadows:  # among the foreground: darker in every channel
            self._remove_shadows(img, fg)
        if self.ghost_every and self.frames_seen % self.ghost_every == 0:
            self._remove_ghosts(img, fg)
        self._update(img, fg, held)
        return fg

    def _update(self, img: Image, fg: Image, held: Image | None) -> None:
        """Eq. (3) every frame for the mean; every ``refresh`` frames for the noise (at the
        rate of ``refresh`` frames, :math:`1 - (1 - \\alpha)^{refresh}`) and for the count of
        frames a pixel has been busy (foreground or held), which absorbs it."""
        busy = fg if held is None else cv2.bitwise_or(fg, held)
        learn = cv2.bitwise_not(busy)
        cv2.accumulateWeighted(img, self.mean, self.alpha, mask=learn)  # eq. (3), background
        if self.alpha_slow > 0:
            slow = fg if held is None else cv2.bitwise_and(fg, cv2.bitwise_not(held))
            cv2.accumulateWeighted(img, self.mean, self.alpha_slow, mask=slow)
        if self.frames_seen % self.refresh:
            return
        d32 = self._d32
        cv2.multiply(self._d, self._d, dst=d32, dtype=cv2.CV_32F)  # d² on the background
        cv2.accumulateWeighted(d32, self.var, self._alpha_refresh, mask=learn)
        if self.absorb_after:
            run = self._run
            cv2.add(run, float(self.refresh), dst=run, mask=busy)  # frames busy in a row
            cv2.bitwise_and(run, 0.0, dst=run, mask=learn)
            done = cv2.compare(run, float(self.absorb_after), cv2.CMP_GE)
            if cv2.countNonZero(done):
                cv2.accumulateWeighted(img, self.mean, 1.0, mask=done)  # absorbed whole
                cv2.bitwise_and(run, 0.0, dst=run, mask=done)
                self._stale = True

    def _remove_shadows(self, img: Image, fg: Image) -> None:
        """Shadow pixels of ``fg`` set to 0: the test of the module docstring on the
        foreground pixels not brighter than the background's neighbourhood in any channel
        (a shadow is darker in every channel), one compiled pass (:func:`shadow_cells`)."""
        lo, hi = self.shadow_ratio
        shadow_cells(img, self._mu8, self._hi, self._mu_grey, self._mu_grey_pad, fg,
                     self.shadow_step, lo, hi, self.shadow_chroma, self.shadow_texture,
                     self.shadow_min_texture, self.shadow_correlation)

    def _remove_ghosts(self, img: Image, fg: Image) -> None:
        """Ghost blobs of ``fg`` reset to the frame and cleared: the test of
        :func:`~mvtrack.detection.ghosts.ghost_blobs` (the outline's edges are the
        background's, not the frame's), the gradients of the background of the last refresh
        and of the frame computed on the outline pixels only (:func:`sobel_at`, exact), over
        a band two pixels wide across each blob's border, inside the box of the still
        foreground (:func:`ghost_window`).

        Only foreground that stood still since the previous test is looked at (pixels busy
        for ``ghost_every`` frames in a row, as the count of the last refresh tells): a
        ghost stays where it is, and an object that moves is never reset into the
        background, however textured the background behind it (a walker in front of a row
        of bicycles)."""
        out = fg
        still = cv2.compare(self._run, float(max(self.ghost_every - self.refresh, 1)),
                            cv2.CMP_GE)
        fg_still = cv2.bitwise_and(fg, still)
        win = ghost_window(fg_still)
        if win is None:
            return
        y0, y1, x0, x1 = win  # the still foreground with its outline and ring, and no more
        fg = fg_still[y0:y1, x0:x1]
        try:  # 16-bit labels (dilated as they are) unless there are more than 65535 blobs
            n, labels = cv2.connectedComponents(fg, connectivity=8, ltype=cv2.CV_16U)
        except cv2.error:
            n, labels = cv2.connectedComponents(fg, connectivity=8, ltype=cv2.CV_32S)
        if n <= 1:
            return
        # the outline as a band across the blob's border (the neighbourhood test of eq. (1)
        # leaves a blob a pixel inside the object's edge), labelled by the nearest blob
        outline = cv2.subtract(cv2.dilate(fg, None), cv2.erode(fg, None))
        if labels.dtype == np.uint16:
            labels = cv2.dilate(labels, None)
        else:
            labels = cv2.dilate(labels.astype(np.float32), None).astype(np.int32)
        pts = cv2.findNonZero(outline)
        if pts is None:
            return
        pts = pts.reshape(-1, 2).astype(np.intp)
        e_frame = np.hypot(*sobel_at(img, pts[:, 1] + y0, pts[:, 0] + x0))
        e_back = np.hypot(*sobel_at(self._mu8, pts[:, 1] + y0, pts[:, 0] + x0))
        lab = labels[pts[:, 1], pts[:, 0]]
        s_frame = np.bincount(lab, e_frame, minlength=n)
        s_back = np.bincount(lab, e_back, minlength=n)
        ghost = (s_back > GHOST_RATIO * s_frame).astype(np.uint8) * np.uint8(255)
        ghost[0] = 0
        if not ghost.any():
            return
        # each pixel's blob a ghost or not: a table look-up of 8-bit labels where they fit
        if n <= 256:
            on = cv2.LUT(labels.astype(np.uint8), np.pad(ghost, (0, 256 - n)))
        else:
            on = ghost[labels]
        sel = cv2.bitwise_and(on, fg)
        # reset to the frame with the ring the neighbourhood test left out of the blob
        mean = self.mean[y0:y1, x0:x1]
        cv2.accumulateWeighted(img[y0:y1, x0:x1], mean, 1.0, mask=cv2.dilate(sel, None))
        out = out[y0:y1, x0:x1]
        cv2.bitwise_and(out, cv2.bitwise_not(sel), dst=out)
        run = self._run[y0:y1, x0:x1]
        cv2.bitwise_and(run, 0.0, dst=run, mask=sel)
        self._stale = True

    def rescale(self, size: tuple[int, int]) -> None:
        """Resample the model to a working frame of ``size`` (W, H) (the front end changed
        its working scale)."""
        if self.mean is None:
            return
        mean = cv2.resize(self.mean, size, interpolation=cv2.INTER_AREA)
        var = cv2.resize(self.var, size, interpolation=cv2.INTER_AREA)
        run = cv2.resize(self._run, size, interpolation=cv2.INTER_NEAREST)
        self.bootstrap(np.zeros((size[1], size[0], 3), np.uint8))
        self.mean, self.var, self._run = mean, var, run


def ghost_window(fg_still: Image) -> tuple[int, int, int, int] | None:
    """Rows ``y0:y1`` and columns ``x0:x1`` of the image the ghost test works on: the
    box of the still foreground widened by 2 px (its outline reaches 1 px beyond it, and the
    outline's labels and the reset ring 1 px more), from an even row and column (the
    labeller numbers blobs by 2×2 blocks, so the numbering is the whole image's); None
    without still foreground."""
    x, y, bw, bh = cv2.boundingRect(fg_still)
    if bw == 0:
        return None
    h, w = fg_still.shape
    x0, y0 = max(x - 2, 0), max(y - 2, 0)
    return y0 - y0 % 2, min(y + bh + 2, h), x0 - x0 % 2, min(x + bw + 2, w)


@kernel
def sobel_at(img: Image, ys: NDArray[np.intp], xs: NDArray[np.intp]
             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The 3×3 Sobel derivatives ``(g_x, g_y)`` of the grey levels of BGR ``img``
    (:func:`grey_at`) at the pixels ``(ys, xs)`` only, the border replicated (as
    :func:`cv2.Sobel` with ``ksize=3`` of ``cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)``; whole
    numbers, exact)."""
    h, w = img.shape[:2]
    gx = np.empty(ys.size)
    gy = np.empty(ys.size)
    p = np.empty((3, 3))
    for k in range(ys.size):
        for dy in range(3):
            yy = min(max(ys[k] + dy - 1, 0), h - 1)
            for dx in range(3):
                p[dy, dx] = np.float64(grey_at(img, yy, min(max(xs[k] + dx - 1, 0), w - 1)))
        gx[k] = (p[0, 2] + 2 * p[1, 2] + p[2, 2]) - (p[0, 0] + 2 * p[1, 0] + p[2, 0])
        gy[k] = (p[2, 0] + 2 * p[2, 1] + p[2, 2]) - (p[0, 0] + 2 * p[0, 1] + p[0, 2])
    return gx, gy


@kernel
def _darker(img: Image, mu_hi: Image, y: int, x: int) -> bool:
    """Pixel ``(y, x)`` of ``img`` is not above ``mu_hi`` in any channel."""
    return img[y, x, 0] <= mu_hi[y, x, 0] and img[y, x, 1] <= mu_hi[y, x, 1] and (
        img[y, x, 2] <= mu_hi[y, x, 2])


@kernel
def background_spread(grey: Image, y: int, x: int) -> np.float32:
    """The local spread of the grey background at ``(y, x)``: the standard deviation over
    its 3×3 window, ``sqrt(max(blur(g²) − blur(g)², 0))`` with OpenCV's ``cv2.blur``
    (mirrored border, ``BORDER_REFLECT_101``) in ``float32``: the window's sums are whole
    numbers (exact), scaled by 1/9 in double precision and rounded to ``float32``, as
    OpenCV's box filter does."""
    h, w = grey.shape
    s1 = 0.0
    s2 = 0.0
    for dy in range(-1, 2):
        yy = abs(y + dy)  # mirrored at the top and the bottom (a row of one: itself)
        if yy >= h:
            yy = 2 * h - 2 - yy
        yy = min(max(yy, 0), h - 1)
        for dx in range(-1, 2):
            xx = abs(x + dx)
            if xx >= w:
                xx = 2 * w - 2 - xx
            xx = min(max(xx, 0), w - 1)
            v = np.float64(grey[yy, xx])
            s1 += v
            s2 += v * v
    mean = np.float32(s1 * (1.0 / 9.0))
    var = np.float32(s2 * (1.0 / 9.0)) - mean * mean
    return np.float32(math.sqrt(var)) if var > np.float32(0.0) else np.float32(0.0)


@kernel
def grey_at(img: Image, y: int, x: int) -> np.uint8:
    r"""The grey level of BGR pixel ``(y, x)`` as ``cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)``
    gives it: :math:`(3735 B + 19235 G + 9798 R + 2^{14}) \gg 15` (OpenCV's 8-bit weights
    of 0.114, 0.587, 0.299 in 15-bit fixed point, rounded; tested on every colour)."""
    v = (np.int64(img[y, x, 0]) * 3735 + np.int64(img[y, x, 1]) * 19235
         + np.int64(img[y, x, 2]) * 9798 + 16384) >> 15
    return np.uint8(v)


@kernel
def shadow_cells(
    img: Image, mu8: Image, mu_hi: Image, mu_grey: Image, mu_grey_pad: Image, fg: Image,
    step: int, lo: float, hi: float, chroma: float, texture: float, min_texture: float,
    correlation: float,
) -> None:
    r"""Clear the shadow cells of ``fg`` (in place): the shadow test of the module docstring
    on the candidates among every ``step``-th foreground pixel along each row and column.
    A candidate is a foreground pixel darker in every channel: not above the neighbourhood
    maximum ``mu_hi`` of the background (:math:`\hat\mu` of eq. (1)) in any.

    For a candidate with frame colour :math:`f` and background colour :math:`m` (grey levels
    plus one, so that black has a colour) and brightnesses :math:`L_f = \sum_c f_c`,
    :math:`L_m = \sum_c m_c`:

    - the brightness ratio must lie in ``[lo, hi]``: :math:`lo \, L_m \le L_f \le hi \, L_m`;
    - *colour kept*: :math:`\sum_c |f_c / L_f - m_c / L_m| <` ``chroma``, multiplied out by
      :math:`L_f L_m` (integers), and no texture of its own: the standard deviation
      :math:`s_f` of the frame's grey levels over the 3×3 window at most
      :math:`(L_f / L_m)\, s_m +` ``texture`` (:math:`s_m`: the background's, as
      :func:`background_spread`);
    - or *texture kept*: on a background with :math:`s_m >` ``min_texture``, the correlation
      of the frame's and the background's grey levels over the window above ``correlation``.

    A tested pixel that is a shadow clears the candidates of its ``step`` × ``step`` cell
    (itself at the top left); the cells do not overlap, so the order of the tests does not
    matter. The window statistics are summed in ``float32`` in row order, as NumPy sums the
    nine offsets. The frame's grey levels are computed at the window's pixels
    (:func:`grey_at`, the image's border replicated); ``mu_grey`` is the background's grey
    image and ``mu_grey_pad`` the same padded by one pixel (replicated border).
    """
    h, w = fg.shape
    ninth = np.float32(9.0)
    zero = np.float32(0.0)
    tiny = np.float32(1e-3)
    min_texture32 = np.float32(min_texture)
    correlation32 = np.float32(correlation)
    window = np.empty(9, np.float32)  # the frame's grey levels over the 3×3 window
    for y in range(0, h, step):
        for x in range(0, w, step):
            if fg[y, x] == 0 or not _darker(img, mu_hi, y, x):
                continue
            f0, f1, f2 = np.int64(img[y, x, 0]) + 1, np.int64(img[y, x, 1]) + 1, np.int64(
                img[y, x, 2]) + 1
            m0, m1, m2 = np.int64(mu8[y, x, 0]) + 1, np.int64(mu8[y, x, 1]) + 1, np.int64(
                mu8[y, x, 2]) + 1
            lf, lm = f0 + f1 + f2, m0 + m1 + m2
            if not (lf >= lo * lm and lf <= hi * lm):  # the brightness ratio
                continue
            cross = abs(f0 * lm - m0 * lf) + abs(f1 * lm - m1 * lf) + abs(f2 * lm - m2 * lf)
            shadow = cross < chroma * np.float64(lf * lm)  # the colour kept
            spread = background_spread(mu_grey, y, x)
            sa, saa = zero, zero  # the frame's 3×3 window: sum and sum of squares
            for dy in range(3):
                yy = min(max(y + dy - 1, 0), h - 1)
                for dx in range(3):
                    va = np.float32(grey_at(img, yy, min(max(x + dx - 1, 0), w - 1)))
                    window[3 * dy + dx] = va
                    sa += va
                    saa += va * va
            ma = sa / ninth
            var_a = saa / ninth - ma * ma
            var_a = var_a if var_a > zero else zero
            if shadow:  # ... and no texture of its own
                s_f = np.float32(math.sqrt(var_a))
                shadow = np.float64(s_f) <= (lf / lm) * np.float64(spread) + texture
            if not shadow and spread > min_texture32:  # the background's texture kept
                sb, sbb, sab = zero, zero, zero
                for dy in range(3):
                    for dx in range(3):
                        va = window[3 * dy + dx]
                        vb = np.float32(mu_grey_pad[y + dy, x + dx])
                        sb += vb
                        sbb += vb * vb
                        sab += va * vb
                mb = sb / ninth
                var_b = sbb / ninth - mb * mb
                var_b = var_b if var_b > zero else zero
                cov = sab / ninth - ma * mb
                rho = cov / np.float32(math.sqrt(var_a * var_b + tiny))
                shadow = rho > correlation32
            if shadow:  # the cell of the tested pixel, where it holds candidates
                for yy in range(y, min(y + step, h)):
                    for xx in range(x, min(x + step, w)):
                        if fg[yy, xx] != 0 and _darker(img, mu_hi, yy, xx):
                            fg[yy, xx] = 0


def _bgr(frame: Image) -> Image:
    if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
        raise ValueError(f"frame must be a uint8 image, got {frame.dtype} {frame.shape}")
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR)
    if frame.shape[2] == 1:
        return cv2.cvtColor(frame[:, :, 0], cv2.COLOR_GRAY2BGR)
    return frame
