"""Ground-plane calibration: image pixels → metres on the road.

Two forms:

* four (or more) image–ground point pairs give the homography ``H`` (OpenCV's
  ``findHomography``, least squares over all pairs), with

  .. math::  \\tilde g = H \\tilde p,\\qquad
             g = \\left(\\frac{h_1^T \\tilde p}{h_3^T \\tilde p},
                        \\frac{h_2^T \\tilde p}{h_3^T \\tilde p}\\right),
             \\qquad \\tilde p = (x, y, 1)^T;

* a scale ``s`` metres per pixel, ``H = diag(s, s, 1)`` (a camera looking straight down).

A velocity ``v`` (px/frame) at image point ``p`` maps to the ground velocity ``J(p) v``
(m/frame), with the Jacobian of the homography

.. math::  J_{ij}(p) = \\frac{\\partial g_i}{\\partial p_j}
                     = \\frac{H_{ij} - g_i H_{3j}}{h_3^T \\tilde p},\\qquad i, j \\in \\{1, 2\\},

exact to first order in ``v`` (the speed over one frame is the derivative at the foot point,
not a difference of two mapped points).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mvtrack.analytics.geometry import as_points

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GroundCalibration:
    """An image → ground homography (metres).

    Attributes
    ----------
    H : (3, 3) float64
        Homography from image pixels to ground metres, normalised to ``H[2, 2] = 1`` where
        possible.
    sign : float
        Sign of ``h_3ᵀ p̃`` at the calibration points: image points where it differs map to
        behind the camera (above the horizon) and get NaN.
    residual_m : float
        RMS distance between the mapped image points and their ground points (0 for a scale).
    region : (V, 2) float64 or None
        The calibrated part of the image: the convex hull of the image points (None for a
        scale: everywhere). A homography fitted to four points is only known to hold between
        them; speeds are measured inside this region only.
    """

    H: FloatArray
    sign: float = 1.0
    residual_m: float = 0.0
    region: FloatArray | None = None

    @classmethod
    def from_points(cls, image: ArrayLike, ground: ArrayLike) -> GroundCalibration:
        """Homography from ``N ≥ 4`` image points (px) and their ground points (m).

        Raises
        ------
        ValueError
            Fewer than 4 pairs, unequal counts, non-finite values, or a degenerate layout
            (three of four points on one line, or a map OpenCV cannot fit).
        """
        import cv2

        img = as_points(image, None, "calibration image points")
        gnd = as_points(ground, None, "calibration ground points")
        if img.shape[0] != gnd.shape[0]:
            raise ValueError(f"calibration: {img.shape[0]} image points but {gnd.shape[0]} "
                             "ground points")
        if img.shape[0] < 4:
            raise ValueError(f"calibration needs at least 4 point pairs, got {img.shape[0]}")
        for what, pts in (("image", img), ("ground", gnd)):
            if _collinear_triple(pts):
                raise ValueError(f"calibration: three of the {what} points lie on one line")
        h, _ = cv2.findHomography(img, gnd, 0)
        if h is None or not np.isfinite(h).all() or abs(np.linalg.det(h)) < 1e-15:
            raise ValueError("calibration: the point pairs do not define a homography")
        if abs(h[2, 2]) > 1e-12:
            h = h / h[2, 2]
        w = img @ h[2, :2] + h[2, 2]
        if not (np.all(w > 0) or np.all(w < 0)):
            raise ValueError("calibration: the image points lie on both sides of the horizon")
        sign = float(np.sign(w[0]))
        out = cls(h, sign)
        res = float(np.sqrt(np.mean(np.sum((out.to_ground(img) - gnd) ** 2, axis=1))))
        hull = cv2.convexHull(img.astype(np.float32)).reshape(-1, 2).astype(np.float64)
        return cls(h, sign, res, hull)

    @classmethod
    def from_scale(cls, metres_per_pixel: float) -> GroundCalibration:
        """A uniform scale: ``metres_per_pixel`` on both axes."""
        s = float(metres_per_pixel)
        if not (np.isfinite(s) and s > 0):
            raise ValueError(f"metres_per_pixel must be a positive number, got "
                             f"{metres_per_pixel}")
        return cls(np.diag([s, s, 1.0]))

    def _w(self, xy: FloatArray) -> FloatArray:
        return xy @ self.H[2, :2] + self.H[2, 2]

    def to_ground(self, xy: ArrayLike) -> FloatArray:
        """Ground points (m) of image points (K, 2); NaN beyond the horizon."""
        p = np.asarray(xy, np.float64).reshape(-1, 2)
        w = self._w(p)
        g = (p @ self.H[:2, :2].T + self.H[:2, 2]) / w[:, None]
        g[~(w * self.sign > 0)] = np.nan
        return g

    def jacobian(self, xy: ArrayLike) -> FloatArray:
        """(K, 2, 2) ``∂g/∂p`` at image points (module docstring); NaN beyond the horizon."""
        p = np.asarray(xy, np.float64).reshape(-1, 2)
        w = self._w(p)
        g = (p @ self.H[:2, :2].T + self.H[:2, 2]) / w[:, None]
        jac = (self.H[None, :2, :2] - g[:, :, None] * self.H[None, 2, None, :2]) / w[:, None,
                                                                                     None]
        jac[~(w * self.sign > 0)] = np.nan
        return jac

    def calibrated(self, xy: ArrayLike) -> NDArray[np.bool_]:
        """(K,) which image points lie in the calibrated region (all, for a scale)."""
        from mvtrack.analytics.geometry import inside_polygon

        p = np.asarray(xy, np.float64).reshape(-1, 2)
        if self.region is None:
            return np.isfinite(p).all(axis=1)
        return inside_polygon(p, self.region)

    def metres_per_pixel(self, xy: ArrayLike) -> FloatArray:
        """(K,) local scale ``sqrt(|det J|)``: metres per pixel at image points."""
        return np.sqrt(np.abs(np.linalg.det(self.jacobian(xy))))


def _collinear_triple(pts: FloatArray) -> bool:
    """Whether the points cannot fix a homography: with four, three of them on one line; with
    more, all of them on one line."""
    scale = max(float(np.ptp(pts, axis=0).max()), 1e-12)
    if pts.shape[0] > 4:
        sv = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
        return bool(sv[1] < 1e-9 * max(sv[0], 1e-12))
    i, j, k = np.array([(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]).T
    u, v = pts[j] - pts[i], pts[k] - pts[i]
    area = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
    return bool(np.any(area < 1e-6 * scale * scale))
