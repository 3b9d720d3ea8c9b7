"""Blobs of a mask (:mod:`mvtrack.detection.labelling`): labels and statistics as OpenCV's
labelling with statistics of the whole image gives them."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mvtrack.detection import labelling
from mvtrack.detection.labelling import label_blobs


def _opencv(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    _, labels, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(
        mask, 8, cv2.CV_32S, cv2.CCL_BBDT)
    return labels, stats


def _check(mask: np.ndarray) -> None:
    labels, stats = label_blobs(mask)
    want_labels, want_stats = _opencv(mask)
    np.testing.assert_array_equal(labels, want_labels)
    np.testing.assert_array_equal(stats[1:], want_stats[1:])
    h, w = mask.shape
    np.testing.assert_array_equal(stats[0], [0, 0, w, h, int((mask == 0).sum())])


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("threads", [1, 2])
def test_labels_and_statistics_are_opencvs_of_the_whole_image(threads: int, compiled: bool,
                                                             monkeypatch) -> None:
    """Foreground in a band, at the top or bottom edge, filling whole rows, none at all,
    widths that are and are not a multiple of the labels in a word; one thread or two."""
    if not compiled:  # the plain function the kernel is compiled from
        monkeypatch.setattr(labelling, "blob_stats", labelling.blob_stats.py_func)
    rng = np.random.default_rng(threads)
    old = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        for k in range(150 if compiled else 30):
            mask = np.zeros((int(rng.integers(1, 70)), int(rng.integers(1, 70))), np.uint8)
            mask[rng.random(mask.shape) < rng.uniform(0.0, 0.8)] = 255
            if k % 2:
                mask[: rng.integers(0, mask.shape[0] + 1)] = 0
            if k % 3 == 0:
                mask[rng.integers(0, mask.shape[0] + 1) :] = 0
            if k % 5 == 0:
                mask[rng.integers(0, mask.shape[0]) :] = 255
            _check(mask)
    finally:
        cv2.setNumThreads(old)


def test_more_blobs_than_sixteen_bit_labels_hold() -> None:
    """Isolated pixels two apart: 67 500 blobs, 32-bit labels, the same statistics."""
    mask = np.zeros((300, 900), np.uint8)
    mask[::2, ::2] = 255
    labels, stats = label_blobs(mask)
    assert labels.dtype == np.int32 and len(stats) == 67_501
    _check(mask)
