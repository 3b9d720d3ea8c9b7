r"""The size of an object as a function of the image row of its foot point, learnt from the scene.

With a camera above a ground plane, an object of height :math:`H` whose foot point is at image
row :math:`y` appears :math:`h(y) \approx b_h (y - y_0)` pixels tall, :math:`y_0` the row of
the horizon (a pinhole camera with small tilt; for a walker the width follows likewise):

.. math::

    h(y) = a_h + b_h y, \qquad w(y) = \rho\, h(y).   \qquad (1)

:class:`SizePrior` fits eq. (1) online to the boxes of isolated confirmed tracks (the caller
chooses them): the last ``capacity`` samples are kept in a ring buffer and refitted every
``refit_every`` new ones by iteratively reweighted least squares with Tukey's biweight on the
residuals in units of their median absolute deviation, so a box that holds two people, or a
person and their shadow, does not pull the line; :math:`\rho` is the median of the samples'
``w / h``. The fit is *ready* once it has
``min_samples`` samples spread over at least ``min_spread`` rows.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def robust_line(
    x: FloatArray, y: FloatArray, iterations: int = 10, c: float = 4.685
) -> tuple[float, float, float]:
    """``(a, b, s)``: the line ``y = a + b x`` by IRLS with Tukey's biweight, and the scale.

    ``s`` is 1.4826 × the median absolute residual (the residuals' robust standard
    deviation); weights ``(1 - (r / (c s))²)²`` for ``|r| < c s``, else 0. Starts from
    ordinary least squares.
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    design = np.column_stack([np.ones_like(x), x])
    w = np.ones_like(x)
    a = b = s = 0.0
    for _ in range(iterations):
        sw = np.sqrt(w)
        coef, *_ = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)
        a, b = float(coef[0]), float(coef[1])
        r = y - (a + b * x)
        s = 1.4826 * float(np.median(np.abs(r)))
        if s <= 1e-9:
            break
        u = r / (c * s)
        w_new = np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)
        if np.allclose(w_new, w, atol=1e-6):
            break
        w = w_new
    return a, b, s


def quantile_line(
    x: FloatArray, y: FloatArray, q: float = 0.75, iterations: int = 30
) -> tuple[float, float, float]:
    """``(a, b, s)``: the ``q``-quantile line ``y = a + b x`` (pinball loss, by IRLS).

    Weights ``q / |r|`` above the line and ``(1 - q) / |r|`` below it (residuals floored at
    1e-3 of their scale), starting from :func:`robust_line`; ``s`` as there. Partial bodies
    are the common outlier of blob sizes (a person whose legs match the pavement), so the
    fit of the upper quantile follows whole objects.
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    a, b, s = robust_line(x, y)
    design = np.column_stack([np.ones_like(x), x])
    floor = max(1e-3 * s, 1e-6)
    for _ in range(iterations):
        r = y - (a + b * x)
        w = np.where(r > 0, q, 1.0 - q) / np.maximum(np.abs(r), floor)
        sw = np.sqrt(w)
        coef, *_ = np.linalg.lstsq(design * sw[:, None], y * sw, rcond=None)
        a_new, b_new = float(coef[0]), float(coef[1])
        done = abs(a_new - a) + abs(b_new - b) * (np.abs(x).max() + 1) < 1e-3
        a, b = a_new, b_new
        if done:
            break
    r = y - (a + b * x)
    return a, b, 1.4826 * float(np.median(np.abs(r - np.median(r))))


class SizePrior:
    """Online robust fit of eq. (1): expected box width and height at each foot row.

    Parameters
    ----------
    capacity : int, default 400
        Samples kept (the most recent).
    min_samples : int, default 30
        Samples needed before the prior is :attr:`ready`.
    min_spread : float, default 20
        Rows between the 10th and 90th percentile of the foot rows needed before it is ready
        (a line through one row has no slope).
    refit_every : int, default 10
        New samples between two fits.
    quantile : float or None, default 0.75
        Fit the height line to this quantile (:func:`quantile_line`); None fits the middle
        with Tukey's biweight (:func:`robust_line`).

    Attributes
    ----------
    coef : (2, 2) float64
        ``[[ρ a_h, ρ b_h], [a_h, b_h]]`` of eq. (1): width and height lines (NaN until the
        first fit).
    scale : (2,) float64
        Robust standard deviation of the width and height residuals, pixels.
    """

    def __init__(
        self,
        capacity: int = 400,
        min_samples: int = 30,
        min_spread: float = 20.0,
        refit_every: int = 10,
        quantile: float | None = 0.75,
    ) -> None:
        if capacity < 2 or min_samples < 2 or min_samples > capacity or refit_every < 1:
            raise ValueError(
                "need capacity >= min_samples >= 2 and refit_every >= 1, got "
                f"{capacity}, {min_samples}, {refit_every}"
            )
        if not (math.isfinite(min_spread) and min_spread >= 0):
            raise ValueError(f"min_spread must be a non-negative number, got {min_spread}")
        self.capacity = int(capacity)
        self.min_samples = int(min_samples)
        self.min_spread = float(min_spread)
        self.refit_every = int(refit_every)
        if quantile is not None and not 0.0 < quantile < 1.0:
            raise ValueError(f"quantile must be in (0, 1) or None, got {quantile}")
        self.quantile = quantile
        self.reset()

    def reset(self) -> None:
        """Forget every sample."""
        self._buf = np.zeros((self.capacity, 3))  # foot row, w, h
        self._n = 0  # samples seen
        self._since = 0
        self.coef = np.full((2, 2), np.nan)
        self.scale = np.full(2, np.nan)
        self._ready = False

    @property
    def n_samples(self) -> int:
        """Samples in the buffer."""
        return min(self._n, self.capacity)

    @property
    def ready(self) -> bool:
        """Whether the prior has been fitted on enough, spread-out samples."""
        return self._ready

    def update(self, tlwh: ArrayLike) -> None:
        """Add boxes ``(left, top, width, height)`` of isolated objects; refit when due."""
        boxes = np.asarray(tlwh, np.float64).reshape(-1, 4)
        ok = np.isfinite(boxes).all(axis=1) & (boxes[:, 2] > 0) & (boxes[:, 3] > 0)
        boxes = boxes[ok]
        if len(boxes) == 0:
            return
        if len(boxes) > self.capacity:
            boxes = boxes[-self.capacity :]
        rows = np.column_stack([boxes[:, 1] + boxes[:, 3], boxes[:, 2], boxes[:, 3]])
        idx = (self._n + np.arange(len(rows))) % self.capacity
        self._buf[idx] = rows
        self._n += len(rows)
        self._since += len(rows)
        if self._since >= self.refit_every or not self._ready:
            self._since = 0
            self.fit()

    def fit(self) -> None:
        """Refit eq. (1) on the buffer (:func:`robust_line` for the width and the height)."""
        data = self._buf[: self.n_samples]
        if len(data) < self.min_samples:
            return
        foot = data[:, 0]
        lo, hi = np.percentile(foot, [10, 90])
        if hi - lo < self.min_spread:
            return
        if self.quantile is None:
            a, b, s = robust_line(foot, data[:, 2])
        else:
            a, b, s = quantile_line(foot, data[:, 2], self.quantile)
        if not b > 0:  # objects farther away (higher up) must look smaller
            return
        rho = float(np.median(data[:, 1] / data[:, 2]))
        self.coef[1] = a, b
        self.coef[0] = rho * a, rho * b
        self.scale[:] = rho * s, s
        self._ready = True

    def expected(self, foot_row: ArrayLike) -> FloatArray:
        """Expected ``(w, h)`` at each foot row, shape (M, 2) (NaN while not :attr:`ready`)."""
        y = np.asarray(foot_row, np.float64).reshape(-1)
        if not self._ready:
            return np.full((len(y), 2), np.nan)
        wh = self.coef[:, 0][None, :] + self.coef[:, 1][None, :] * y[:, None]
        return np.maximum(wh, 1.0)

    def ratio(self, tlwh: ArrayLike) -> FloatArray:
        """Box size over the expected size at its foot row, ``(w / w(y), h / h(y))``, (M, 2)."""
        boxes = np.asarray(tlwh, np.float64).reshape(-1, 4)
        return boxes[:, 2:] / self.expected(boxes[:, 1] + boxes[:, 3])

    def plausible(
        self, tlwh: ArrayLike, low: tuple[float, float] = (0.3, 0.5), high: float = 2.0
    ) -> NDArray[np.bool_]:
        """Which boxes some object of the scene could have (all True while not ready).

        A box is implausible when its width or height is below ``low`` (w, h) times the
        expected size at its foot row, or its height above ``high`` times it (a box may be
        wider than one object: several walk side by side).
        """
        boxes = np.asarray(tlwh, np.float64).reshape(-1, 4)
        if not self._ready:
            return np.ones(len(boxes), bool)
        r = self.ratio(boxes)
        return (r[:, 0] >= low[0]) & (r[:, 1] >= low[1]) & (r[:, 1] <= high)

    def scale_at(self, foot_row: float) -> float:
        """Expected height at ``foot_row``, or NaN while not ready (to size morphology)."""
        return float(self.expected([foot_row])[0, 1])
