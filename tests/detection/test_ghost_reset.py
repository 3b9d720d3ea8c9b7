"""The disturbance map's compiled ghost reset (:func:`mvtrack.detection.ghosts.ghost_reset`)
against the plain NumPy/OpenCV computation it replaces (:func:`ghost_pixels` on the rounded
background, then the reset of its pixels)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mvtrack.detection import ghosts
from mvtrack.detection.ghosts import ghost_pixels, reset_ghosts


def _reference(mask, grey, background):  # type: ignore[no-untyped-def]
    mask, background = mask.copy(), background.copy()
    sel = ghost_pixels(mask, grey, cv2.convertScaleAbs(background))
    if sel is not None:
        background[sel] = grey[sel]
        mask[sel] = 0
    return sel is not None, mask, background


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("seed", range(6))
def test_ghost_reset_matches_ghost_pixels(seed, compiled, monkeypatch) -> None:
    if not compiled:  # the plain function the kernel is compiled from
        monkeypatch.setattr(ghosts, "ghost_reset", ghosts.ghost_reset.py_func)
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(2, 40)), int(rng.integers(2, 50)))
    grey = rng.integers(0, 256, shape).astype(np.uint8)
    # half-way grey levels too: convertScaleAbs rounds them to even
    background = (rng.integers(0, 511, shape) / 2).astype(np.float32)
    if seed % 2:  # smooth frames, sharp backgrounds: ghosts
        grey = cv2.GaussianBlur(grey, (0, 0), 3.0)
    mask = np.where(rng.random(shape) < (0.2 + 0.1 * seed), 255, 0).astype(np.uint8)
    mask = cv2.dilate(mask, None) if seed > 2 else mask  # blobs reaching the border
    want, ref_mask, ref_bg = _reference(mask, grey, background)
    got = reset_ghosts(mask, grey, background)
    assert got == want
    np.testing.assert_array_equal(mask, ref_mask)
    np.testing.assert_array_equal(background, ref_bg)
    if seed == 1:
        assert got  # the test does reach the reset


def test_reset_ghosts_without_blobs_changes_nothing() -> None:
    grey = np.full((5, 6), 9, np.uint8)
    background = np.zeros((5, 6), np.float32)
    mask = np.zeros((5, 6), np.uint8)
    assert not reset_ghosts(mask, grey, background)
    assert not background.any() and not mask.any()
