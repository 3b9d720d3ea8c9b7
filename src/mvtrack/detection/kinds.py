r"""The kinds of object a scene holds and their size at every image position, learnt from it.

A fixed camera looks at a ground plane. An object of a given kind (a car, a bus, a walker)
whose box stands at image point :math:`(x, y)` (the centre of its bottom edge, where it meets
the ground) appears :math:`S(x, y)` times its kind's size, and for a pinhole camera the scale
of the ground plane is an affine function of the image position (the inverse depth of a
plane is affine in the image coordinates; it vanishes on the horizon):

.. math::

    (w, h) \approx S(x, y)\,(W_k, H_k), \qquad S(x, y) = a + b\,x + c\,y,   \qquad (1)

one scale law for the whole scene and one size :math:`(W_k, H_k)` per kind :math:`k`.
Nothing about the kinds is built in: :class:`KindModel` fits eq. (1) to the boxes of objects
the tracker followed on their own (the caller chooses them), alternating

1. the scale law, by iteratively reweighted least squares (Tukey's biweight) of the box's
   geometric size :math:`\sqrt{w h}` divided by its kind's :math:`\sqrt{W_k H_k}` on
   :math:`(1, x, y)`;
2. the kinds, as the clusters of the samples' log sizes :math:`(\log w/S, \log h/S)`: k-means
   for 1 … ``max_kinds`` clusters, the number with the least Bayesian information criterion
   of a Gaussian per cluster; a cluster with less than ``min_share`` of the samples is not a
   kind (it is what merged or broken blobs look like) and its samples are left out.

:meth:`KindModel.expected` gives every kind's size at any position; :meth:`KindModel.match`
the kind that explains a box best, as one object or as a row or column of objects of that
kind, and how far the box is from it in units of the kind's spread.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.jit import kernel

FloatArray = NDArray[np.float64]


def robust_plane(x: FloatArray, y: FloatArray, z: FloatArray, weight: FloatArray | None = None,
                 iterations: int = 8, c: float = 4.685, ridge: float = 1e-3,
                 relative: bool = False) -> FloatArray:
    """``(a, b, c)`` of ``z ≈ a + b x + c y`` by IRLS with Tukey's biweight.

    ``weight`` (default 1) multiplies each sample's IRLS weight. ``x`` and ``y`` are centred
    and scaled inside; ``ridge`` (relative to the total weight) pulls the slopes towards 0
    when the samples do not span both axes. Starts from weighted least squares.

    ``relative``: the errors are proportional to ``z`` (sizes: a box is measured to a share
    of its size, far and near alike), so the residuals are ``(z - ẑ) / z`` — least squares
    with weights ``1 / z²`` — and their scale is the weighted median of their absolute
    values: many small samples do not make the few large ones outliers.
    """
    prior = np.ones_like(z) if weight is None else np.asarray(weight, np.float64)
    mx, my = float(np.average(x, weights=prior)), float(np.average(y, weights=prior))
    sx, sy = float(np.std(x)) or 1.0, float(np.std(y)) or 1.0
    design = np.column_stack([np.ones_like(x), (x - mx) / sx, (y - my) / sy])
    unit = 1.0 / np.maximum(np.abs(z), 1e-12) if relative else np.ones_like(z)
    base = prior * unit**2
    penalty = np.diag([0.0, ridge, ridge]) * base.sum()
    w = base.copy()
    coef = np.zeros(3)
    for _ in range(iterations):
        dw = design * w[:, None]
        coef = np.linalg.solve(dw.T @ design + penalty, dw.T @ z)
        r = (z - design @ coef) * unit
        a = np.abs(r)
        s = 1.4826 * (_weighted_median(a, prior) if relative else float(np.median(a)))
        if s <= 1e-9:
            break
        u = r / (c * s)
        w = base * np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
    a, b1, c1 = coef
    return np.array([a - b1 * mx / sx - c1 * my / sy, b1 / sx, c1 / sy])


def _weighted_median(values: FloatArray, weight: FloatArray) -> float:
    """The weighted median of ``values``."""
    order = np.argsort(values)
    cum = np.cumsum(weight[order])
    return float(values[order][np.searchsorted(cum, 0.5 * cum[-1])])


def _kmeans(points: FloatArray, weight: FloatArray, k: int, iterations: int = 20
            ) -> tuple[FloatArray, NDArray[np.intp]]:
    """Centres and labels of ``k`` weighted clusters (deterministic start: weighted quantiles
    along the axis of largest spread; then Lloyd's iterations, :func:`lloyd`)."""
    axis = int(np.argmax(points.std(axis=0)))
    order = np.argsort(points[:, axis])
    cum = np.cumsum(weight[order]) / weight.sum()
    start = order[np.minimum(np.searchsorted(cum, (np.arange(k) + 0.5) / k), len(order) - 1)]
    centres = np.ascontiguousarray(points[start])
    labels = np.zeros(len(points), np.intp)
    lloyd(np.ascontiguousarray(points, np.float64), np.ascontiguousarray(weight, np.float64),
          centres, labels, iterations)
    return centres, labels


@kernel
def pairwise_sum(a: FloatArray) -> float:
    """``a.sum()`` as NumPy adds a contiguous float array (pairwise, eight partial sums
    under 128 values), to the bit."""
    n = a.size
    if n < 8:
        s = 0.0
        for i in range(n):
            s += a[i]
        return s
    if n <= 128:
        r = a[:8].copy()
        m = n - n % 8
        for i in range(8, m, 8):
            for j in range(8):
                r[j] += a[i + j]
        s = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        for i in range(m, n):
            s += a[i]
        return s
    half = n // 2
    half -= half % 8
    return pairwise_sum(a[:half]) + pairwise_sum(a[half:])


@kernel
def lloyd(points: FloatArray, weight: FloatArray, centres: FloatArray,
          labels: NDArray[np.intp], iterations: int) -> None:
    """Lloyd's iterations of weighted k-means from ``centres`` (K, D), in place: each point
    to its nearest centre (squared distance, the first of equals), each centre to the
    weighted mean of its points, until the labels repeat or ``iterations`` passes. The
    same sums in the same order as NumPy's ``((p - c) ** 2).sum(axis=1)`` and
    ``np.average(points, axis=0, weights=w)`` (finite ``points``, ``D < 8``)."""
    n, dim = points.shape
    k = centres.shape[0]
    new = np.empty(n, np.intp)
    member = np.empty(n)
    for it in range(iterations):
        for i in range(n):
            best, arg = np.inf, 0
            for j in range(k):
                d = 0.0
                for c in range(dim):
                    e = points[i, c] - centres[j, c]
                    d += e * e
                if d < best:
                    best, arg = d, j
            new[i] = arg
        if it > 0 and (new == labels).all():
            break
        labels[:] = new
        for j in range(k):  # each centre: sum of w p in point order over sum of w
            m = 0
            num = np.zeros(dim)
            for i in range(n):
                if labels[i] == j:
                    for c in range(dim):
                        num[c] += points[i, c] * weight[i]
                    member[m] = weight[i]
                    m += 1
            if m:
                den = pairwise_sum(member[:m])
                for c in range(dim):
                    centres[j, c] = num[c] / den


def _bic(points: FloatArray, weight: FloatArray, centres: FloatArray,
         labels: NDArray[np.intp], floor: float) -> float:
    """Bayesian information criterion of a hard-assigned mixture of axis-aligned Gaussians,
    each sample counted with its weight (normalised to a mean of 1)."""
    n, dim = points.shape
    wt = weight * (n / weight.sum())
    k = len(centres)
    ll = 0.0
    for j in range(k):  # k ≤ 3 clusters
        sel = labels == j
        if not sel.any():
            continue
        p, w = points[sel], wt[sel]
        var = np.maximum(np.average((p - centres[j]) ** 2, axis=0, weights=w), floor**2)
        ll += w.sum() * math.log(w.sum() / n)
        ll -= 0.5 * (w.sum() * np.log(2 * np.pi * var).sum()
                     + (w[:, None] * (p - centres[j]) ** 2 / var).sum())
    params = k * (2 * dim) + (k - 1)
    return -2.0 * ll + params * math.log(n)


class KindModel:
    """Kinds of object and the scene's scale law, eq. (1), fitted online (module docstring).

    Parameters
    ----------
    capacity : int, default 2000
        Samples kept (a ring buffer of the latest).
    min_samples : int, default 30
        Samples before the model is ready.
    refit_every : int, default 20
        New samples between refits (at least half the samples kept).
    max_kinds : int, default 3
        Most kinds.
    min_share : float, default 0.1
        Least share of the samples a kind holds.
    min_spread : float, default 0.1
        Floor of a kind's spread (standard deviation of the log size).

    Attributes
    ----------
    plane : (3,) float
        ``(a, b, c)`` of the scale law :math:`S = a + b x + c y` (``S`` in pixels of a kind
        of size 1).
    sizes : (K, 2) float
        :math:`(W_k, H_k)` of each kind (at ``S = 1``), ordered by area.
    spread : (K, 2) float
        Standard deviation of :math:`\\log w` and :math:`\\log h` within each kind.
    share : (K,) float
        Share of the samples in each kind.
    """

    def __init__(self, capacity: int = 2000, min_samples: int = 30, refit_every: int = 20,
                 max_kinds: int = 3, min_share: float = 0.1, min_spread: float = 0.1) -> None:
        if capacity < min_samples or min_samples < 3:
            raise ValueError(f"need 3 <= min_samples <= capacity, got {min_samples}, {capacity}")
        if not 0 < min_share < 0.5:
            raise ValueError(f"min_share must be in (0, 0.5), got {min_share}")
        if max_kinds < 1:
            raise ValueError(f"max_kinds must be >= 1, got {max_kinds}")
        self.capacity = int(capacity)
        self.min_samples = int(min_samples)
        self.refit_every = int(refit_every)
        self.max_kinds = int(max_kinds)
        self.min_share = float(min_share)
        self.min_spread = float(min_spread)
        self.fit_samples = 400
        self.reset()

    def reset(self) -> None:
        """Forget every sample and the fit."""
        self._buf = np.zeros((self.capacity, 5))  # x, y (bottom centre), w, h, weight
        self.n_samples = 0
        self._next = 0
        self._since = 0
        self.plane = np.array([1.0, 0.0, 0.0])
        self.sizes = np.zeros((0, 2))
        self.spread = np.zeros((0, 2))
        self.share = np.zeros(0)
        self._range = np.array([1.0, 1.0])  # scale limits: the fit is not extrapolated wildly

    @property
    def ready(self) -> bool:
        """Whether the kinds are known."""
        return len(self.sizes) > 0

    @property
    def samples(self) -> FloatArray:
        """The samples kept, ``(x, y_bottom, w, h, weight)``."""
        return self._buf[: self.n_samples]

    def update(self, tlwh: ArrayLike, weight: ArrayLike | None = None) -> None:
        """Add the boxes ``tlwh`` (M, 4) of objects; refit when due.

        ``weight`` (M,) is each box's weight in the fit (default: its area, so that the
        many small blobs of clutter and fragments weigh little against whole objects).
        """
        b = np.asarray(tlwh, np.float64).reshape(-1, 4)
        wt = b[:, 2] * b[:, 3] if weight is None else np.asarray(weight, np.float64).reshape(-1)
        ok = (b[:, 2] > 0) & (b[:, 3] > 0) & np.isfinite(b).all(axis=1) & (wt > 0)
        b, wt = b[ok], wt[ok]
        if len(b) == 0:
            return
        rows = np.column_stack([b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3], b[:, 2], b[:, 3], wt])
        rows = rows[-self.capacity :]
        idx = (self._next + np.arange(len(rows))) % self.capacity
        self._buf[idx] = rows
        self._next = int((self._next + len(rows)) % self.capacity)
        self.n_samples = min(self.n_samples + len(rows), self.capacity)
        self._since += len(rows)
        due = max(self.refit_every, self.n_samples // 2)  # refits grow rarer as samples pile up
        if self.n_samples >= self.min_samples and (not self.ready or self._since >= due):
            self.fit()

    def fit(self) -> None:
        """Refit the scale law and the kinds to the samples kept."""
        s = self.samples
        if len(s) < self.min_samples:
            return
        self._since = 0
        if len(s) > self.fit_samples:  # evenly spaced over the buffer: cost bounded
            s = s[np.linspace(0, len(s) - 1, self.fit_samples).astype(np.intp)]
        x, y, w, h, wt = s.T
        g = np.sqrt(w * h)
        logwh = np.log(np.column_stack([w, h]))
        labels = np.zeros(len(s), np.intp)
        size_of = np.zeros(1)  # log geometric size of each kind
        keep = np.ones(len(s), bool)
        for _ in range(3):  # alternate the scale law and the kinds
            plane = robust_plane(x[keep], y[keep], g[keep] / np.exp(size_of[labels[keep]]),
                                 wt[keep], relative=True)
            scale = self._clip_scale(plane, x, y, keep)
            norm = logwh - np.log(scale)[:, None]
            labels, keep, centres = self._cluster(norm, wt)
            size_of = centres.mean(axis=1)
        self.plane = plane
        order = np.argsort(size_of)
        self.sizes = np.exp(centres[order])
        spread = []
        for j in order:  # the few kinds: 1.4826 × the weighted median absolute deviation
            sel = keep & (labels == j)
            dev = np.abs(norm[sel] - centres[j])
            spread.append([1.4826 * _weighted_median(dev[:, a], wt[sel]) for a in (0, 1)])
        self.spread = np.maximum(np.array(spread), self.min_spread)
        share = np.bincount(labels[keep], wt[keep], minlength=len(centres))[order]
        self.share = share / max(share.sum(), 1e-12)

    def _clip_scale(self, plane: FloatArray, x: FloatArray, y: FloatArray,
                    keep: NDArray[np.bool_]) -> FloatArray:
        """The scale law at the samples, kept within the range it takes over them (and
        remembered, so that :meth:`scale` does not extrapolate past it by more than 2×)."""
        s = plane[0] + plane[1] * x + plane[2] * y
        inside = s[keep]
        pos = inside[inside > 0]
        base = float(np.median(pos)) if pos.size else 1.0
        self._range = np.array([max(pos.min() if pos.size else base, 1e-3 * base) / 2.0,
                                (pos.max() if pos.size else base) * 2.0])
        return np.clip(s, *self._range)

    def _cluster(self, norm: FloatArray, weight: FloatArray
                 ) -> tuple[NDArray[np.intp], NDArray[np.bool_], FloatArray]:
        """Labels, the samples in a kind, and the kinds' centres (log sizes at S = 1)."""
        best = None
        for k in range(1, self.max_kinds + 1):  # at most three candidate numbers of kinds
            if len(norm) < 5 * k:
                break
            centres, labels = _kmeans(norm, weight, k)
            bic = _bic(norm, weight, centres, labels, self.min_spread)
            if best is None or bic < best[0]:
                best = (bic, centres, labels)
        assert best is not None
        _, centres, labels = best
        share = np.bincount(labels, weight, minlength=len(centres)) / weight.sum()
        kinds = np.flatnonzero(share >= self.min_share)
        if kinds.size == 0:
            kinds = np.array([int(share.argmax())])
        remap = np.full(len(centres), -1)
        remap[kinds] = np.arange(len(kinds))
        new = remap[labels]
        keep = new >= 0
        return np.maximum(new, 0), keep, centres[kinds]

    def scale(self, x: ArrayLike, y: ArrayLike) -> FloatArray:
        """:math:`S(x, y)` of eq. (1) at bottom-centre points, within the learnt range."""
        x = np.asarray(x, np.float64)
        y = np.asarray(y, np.float64)
        s = self.plane[0] + self.plane[1] * x + self.plane[2] * y
        return np.clip(s, *self._range)

    def standing(self, tlwh: ArrayLike) -> NDArray[np.bool_]:
        """Whether each box ``tlwh`` (M, 4) stands below the horizon: the scale law of
        eq. (1), not clipped, is positive at its bottom centre (the ground plane's inverse
        depth vanishes on the horizon; nothing that stands on the ground has its foot above
        it). True for every box while the model is not ready."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4)
        if not self.ready:
            return np.ones(len(b), bool)
        s = self.plane[0] + self.plane[1] * (b[:, 0] + b[:, 2] / 2) + self.plane[2] * (
            b[:, 1] + b[:, 3])
        return s > 0

    def expected(self, tlwh: ArrayLike) -> FloatArray:
        """(M, K, 2): the size of each kind standing where each box ``tlwh`` (M, 4) stands."""
        b = np.asarray(tlwh, np.float64).reshape(-1, 4)
        s = self.scale(b[:, 0] + b[:, 2] / 2, b[:, 1] + b[:, 3])
        return s[:, None, None] * self.sizes[None, :, :]

    def match(self, tlwh: ArrayLike, max_parts: int = 4) -> tuple[
            NDArray[np.intp], NDArray[np.intp], FloatArray]:
        """The kind and the row or column of objects that explain each box best.

        For each box, kind ``k`` and counts ``(n_x, n_y)`` with ``n_x n_y ≤ max_parts`` and
        one of them 1, the distance of the box's part ``(w / n_x, h / n_y)`` to the kind's
        size in units of its spread,

        .. math:: z = \\big\\| (\\log(w / n_x W_k S), \\log(h / n_y H_k S)) / \\sigma_k \\big\\|,

        plus :math:`\\log_2(n_x n_y)` (one object is the simpler explanation: a spread more
        for each doubling), is least.

        Returns
        -------
        kind : (M,) int
            Index into :attr:`sizes` (-1 while the model is not ready).
        parts : (M, 2) int
            ``(n_x, n_y)``.
        z : (M,) float
            The distance of the best choice (without the penalty; inf while not ready).
        """
        b = np.asarray(tlwh, np.float64).reshape(-1, 4)
        m = len(b)
        if not self.ready or m == 0:
            return np.full(m, -1), np.ones((m, 2), np.intp), np.full(m, np.inf)
        exp = self.expected(b)  # (M, K, 2)
        counts = [(1, 1)] + [(n, 1) for n in range(2, max_parts + 1)] + [
            (1, n) for n in range(2, max_parts + 1)]
        nxy = np.array(counts, np.float64)  # (C, 2)
        logr = (np.log(b[:, None, None, 2:]) - np.log(nxy[None, None, :, :])
                - np.log(exp[:, :, None, :]))  # (M, K, C, 2)
        sd = self.spread[None, :, None, :]
        z = np.sqrt(((logr / sd) ** 2).sum(axis=3))
        penalty = np.log2(nxy.prod(axis=1))[None, None, :]
        cost = (z + penalty).reshape(m, -1)
        best = cost.argmin(axis=1)
        kk, cc = np.divmod(best, len(counts))
        return kk, nxy[cc].astype(np.intp), z.reshape(m, -1)[np.arange(m), best]
