"""The colour background's shadow test (:func:`mvtrack.detection.colourbg.shadow_cells`)
against an independent, vectorised NumPy statement of the same test, and against its own
plain-Python function, bit for bit."""

from __future__ import annotations

import cv2
import numba
import numpy as np
import pytest

from mvtrack.detection.colourbg import (
    ColourBackground,
    background_spread,
    grey_at,
    shadow_cells,
)


def _reference(img, mu8, mu_hi, mu_grey_pad, mu_spread, fg, step, lo, hi, chroma, texture,
               min_texture, correlation):
    """The test stated over arrays: the candidates (foreground not brighter than the
    background's neighbourhood maximum in any channel, as whole images), gathers at them, the
    window statistics summed in float32 over the nine offsets in row order."""
    up = cv2.subtract(img, mu_hi)
    cand = ((fg > 0) & (up.max(axis=2) == 0)).astype(np.uint8) * 255
    fg = fg.copy()
    ys, xs = np.nonzero(cand[::step, ::step])
    ys, xs = ys * step, xs * step
    f = img[ys, xs].astype(np.int64) + 1
    m = mu8[ys, xs].astype(np.int64) + 1
    lf, lm = f.sum(axis=1), m.sum(axis=1)
    sel = (lf >= lo * lm) & (lf <= hi * lm)
    ys, xs, f, m, lf, lm = ys[sel], xs[sel], f[sel], m[sel], lf[sel], lm[sel]
    cross = np.abs(f * lm[:, None] - m * lf[:, None]).sum(axis=1)
    shadow = cross < chroma * (lf * lm).astype(np.float64)
    grey = cv2.copyMakeBorder(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), 1, 1, 1, 1,
                              cv2.BORDER_REPLICATE)

    def stats(a, b, yy, xx):
        z = np.zeros(yy.size, np.float32)
        sa, saa, sb, sbb, sab = z.copy(), z.copy(), z.copy(), z.copy(), z.copy()
        for dy in range(3):
            for dx in range(3):
                va = a[yy + dy, xx + dx].astype(np.float32)
                vb = b[yy + dy, xx + dx].astype(np.float32)
                sa += va
                saa += va * va
                sb += vb
                sbb += vb * vb
                sab += va * vb
        ma, mb = sa / 9.0, sb / 9.0
        va = np.maximum(saa / 9.0 - ma * ma, 0.0)
        vb = np.maximum(sbb / 9.0 - mb * mb, 0.0)
        return np.sqrt(va), (sab / 9.0 - ma * mb) / np.sqrt(va * vb + 1e-3)

    spread = mu_spread[ys, xs]
    s_f, _ = stats(grey, mu_grey_pad, ys, xs)
    shadow &= s_f <= (lf / lm) * spread + texture
    rest = ~shadow & (spread > min_texture)
    _, rho = stats(grey, mu_grey_pad, ys[rest], xs[rest])
    shadow[rest] = rho > correlation
    for y, x in zip(ys[shadow], xs[shadow], strict=True):
        cell = cand[y:y + step, x:x + step] != 0
        fg[y:y + step, x:x + step][cell] = 0
    return fg


def _scene(seed: int, h: int = 61, w: int = 83):
    """A textured background, a frame with dark patches (shadows of its colour and texture,
    shadows of another colour) and bright and dark objects, and its candidates."""
    rng = np.random.default_rng(seed)
    bg = rng.integers(40, 220, (h, w, 3)).astype(np.uint8)
    bg = cv2.GaussianBlur(bg, (0, 0), rng.uniform(0.5, 2.0))
    frame = bg.copy()
    for _ in range(6):
        y, x = rng.integers(0, h - 8), rng.integers(0, w - 8)
        hh, ww = rng.integers(4, 20), rng.integers(4, 20)
        kind = rng.integers(3)
        region = frame[y:y + hh, x:x + ww].astype(np.float64)
        if kind == 0:  # a shadow: the same colour, darker
            region *= rng.uniform(0.3, 0.9)
        elif kind == 1:  # a bluish shadow
            region *= rng.uniform(0.4, 0.9, 3)
        else:  # an object of its own
            region[:] = rng.integers(0, 255, region.shape)
        frame[y:y + hh, x:x + ww] = np.clip(region, 0, 255).astype(np.uint8)
    mu8 = bg
    mu_grey = cv2.cvtColor(mu8, cv2.COLOR_BGR2GRAY)
    mu_grey_pad = cv2.copyMakeBorder(mu_grey, 1, 1, 1, 1, cv2.BORDER_REPLICATE)
    g = mu_grey.astype(np.float32)
    mean = cv2.blur(g, (3, 3))
    mu_spread = cv2.sqrt(cv2.max(cv2.blur(g * g, (3, 3)) - mean * mean, 0.0))
    mu_hi = cv2.dilate(mu8, np.ones((3, 3), np.uint8))
    changed = (np.abs(frame.astype(int) - mu8.astype(int)).max(axis=2) > 8)
    fg = ((changed | (rng.random((h, w)) < 0.05)) * 255).astype(np.uint8)
    return frame, mu8, mu_hi, mu_grey, mu_grey_pad, mu_spread, fg


PARAMS = (0.2, 0.95, 0.03, 2.0, 3.0, 0.8)


@pytest.mark.parametrize("step", [1, 2, 3])
@pytest.mark.parametrize("seed", range(6))
def test_shadow_cells_equal_the_array_statement(step: int, seed: int) -> None:
    frame, mu8, mu_hi, mu_grey, mu_grey_pad, mu_spread, fg = _scene(seed)
    want = _reference(frame, mu8, mu_hi, mu_grey_pad, mu_spread, fg, step, *PARAMS)
    for fn in (shadow_cells, shadow_cells.py_func):
        got = fg.copy()
        fn(frame, mu8, mu_hi, mu_grey, mu_grey_pad, got, step, *PARAMS)
        np.testing.assert_array_equal(got, want)
    # the scenes exercise every branch: shadows cleared, candidates kept, brighter pixels
    # not tested
    darker = (frame <= mu_hi).all(axis=2)
    assert (want != fg).any() and (want[(fg > 0) & darker] > 0).any()
    assert ((fg > 0) & ~darker).any()


def test_dark_copy_of_the_road_is_shadow_its_own_texture_is_not() -> None:
    """Through the model: a region darkened by a factor of 0.6 is cleared; the same region
    darkened and given a texture of its own stays foreground."""
    rng = np.random.default_rng(3)
    bg = np.full((60, 80, 3), (120, 130, 125), np.uint8)
    bg = np.clip(bg + rng.normal(0, 1.0, bg.shape), 0, 255).astype(np.uint8)
    model = ColourBackground(jitter=0)
    model.bootstrap(bg)
    frame = bg.copy()
    frame[10:30, 10:30] = (bg[10:30, 10:30] * 0.6).astype(np.uint8)  # a shadow
    dark = (bg[10:30, 45:65] * 0.6).astype(np.float64)
    dark[::2] *= 0.5  # stripes: texture the road does not have
    frame[10:30, 45:65] = dark.astype(np.uint8)
    fg = model.apply(frame)
    assert fg[12:28, 12:28].mean() < 0.05 * 255
    assert fg[12:28, 47:63].mean() > 0.9 * 255


@pytest.mark.parametrize("shape", [(48, 64), (1, 9), (9, 1), (2, 2)])
def test_background_spread_equals_opencvs_box_filter(shape) -> None:
    """The 3×3 spread of the grey background at any pixel, borders included, bit for bit
    what ``cv2.blur`` gives over the whole image (and so what the shadow test used)."""
    rng = np.random.default_rng(shape[0])
    grey = rng.integers(0, 256, shape).astype(np.uint8)
    grey[: shape[0] // 2] //= 16  # flat parts as well: a spread of 0
    g = grey.astype(np.float32)
    mean = cv2.blur(g, (3, 3))
    want = cv2.sqrt(cv2.max(cv2.blur(g * g, (3, 3)) - mean * mean, 0.0)).reshape(shape)
    for fn in (background_spread, background_spread.py_func):
        got = np.array([[fn(grey, y, x) for x in range(shape[1])] for y in range(shape[0])],
                       np.float32)
        np.testing.assert_array_equal(got, want)


def test_grey_at_is_opencvs_grey_for_every_colour() -> None:
    """All 2²⁴ colours through the compiled function, a sample through the plain one."""
    v = np.arange(1 << 24, dtype=np.uint32)
    img = np.stack([v & 255, (v >> 8) & 255, v >> 16], axis=-1).astype(np.uint8)
    img = img.reshape(4096, 4096, 3)
    want = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    got = _grey_image(img)
    np.testing.assert_array_equal(got, want)
    rng = np.random.default_rng(0)
    for y, x in rng.integers(0, 4096, (500, 2)):
        assert grey_at.py_func(img, int(y), int(x)) == want[y, x]


@numba.njit
def _grey_image(img: np.ndarray) -> np.ndarray:
    out = np.empty(img.shape[:2], np.uint8)
    for y in range(img.shape[0]):
        for x in range(img.shape[1]):
            out[y, x] = grey_at(img, y, x)
    return out
