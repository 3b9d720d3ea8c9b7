"""Flat wings at a blob's base cut off (:mod:`mvtrack.detection.wings`): a walker's sun shadow,
walkers joined by their shadows; against a per-blob loop written from the definition."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from mvtrack.detection.wings import cut_flat_wings, wing_parts


def label(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    _, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8) * 255, 8)
    return labels, np.arange(1, len(stats)), stats


def oracle(mask: np.ndarray, tau: float) -> list[tuple[float, float, float, float, float]]:
    """One blob at a time, one column at a time, from the module's definition."""
    labels, ids, _ = label(mask)
    out = []
    for i in ids:
        m = labels == i
        base = np.flatnonzero(m.any(axis=1)).max()
        cols = np.flatnonzero(m.any(axis=0))
        height = {c: base - np.flatnonzero(m[:, c]).min() + 1 for c in cols}
        top = max(height.values())
        tall = [c for c in cols if height[c] >= tau * top]
        runs: list[list[int]] = []
        for c in tall:
            if runs and c == runs[-1][-1] + 1:
                runs[-1].append(c)
            else:
                runs.append([c])
        for run in runs:
            rows = np.flatnonzero(m[:, run].any(axis=1))
            out.append((run[0] - 0.5, rows[0] - 0.5, float(len(run)), float(rows[-1] - rows[0] + 1),
                        float(m[:, run].sum())))
    return sorted(out)


def walker(mask: np.ndarray, x: int, feet: int, w: int = 12, h: int = 40) -> None:
    mask[feet - h : feet, x : x + w] = True


def test_a_walkers_shadow_on_the_ground_is_cut_off() -> None:
    m = np.zeros((80, 120), bool)
    walker(m, 60, 70)
    m[62:70, 20:60] = True  # his shadow, flat, to the left of his feet
    labels, ids, stats = label(m)
    boxes, _, area = cut_flat_wings(labels, ids, stats, 0.3)
    np.testing.assert_allclose(boxes, [[59.5, 29.5, 12, 40]])
    assert area[0] == 12 * 40


def test_walkers_joined_by_their_shadows_are_two_an_arm_is_not_cut() -> None:
    m = np.zeros((80, 160), bool)
    walker(m, 30, 70)
    walker(m, 100, 66, h=36)  # farther: feet higher, smaller
    m[62:70, 42:100] = True  # the shadow between them
    m[45:48, 112:125] = True  # an arm held out at mid-height: its columns reach the base
    labels, ids, stats = label(m)
    boxes, src, _ = cut_flat_wings(labels, ids, stats, 0.3)
    order = np.argsort(boxes[:, 0])
    np.testing.assert_allclose(boxes[order], [[29.5, 29.5, 12, 40], [99.5, 29.5, 25, 36]])
    assert (src == 0).all()


def test_a_car_keeps_its_box_and_tau_zero_cuts_nothing() -> None:
    m = np.zeros((60, 100), bool)
    m[20:36, 10:60] = True  # a car from the side: columns of one height
    m[24:36, 8:10] = True  # its rounded front, a little lower
    labels, ids, stats = label(m)
    boxes, _, _ = cut_flat_wings(labels, ids, stats, 0.3)
    np.testing.assert_allclose(boxes, [[7.5, 19.5, 52, 16]])
    m[33:36, 60:90] = True  # and a flat shadow behind it
    labels, ids, stats = label(m)
    boxes0, _, area0 = cut_flat_wings(labels, ids, stats, 0.0)
    np.testing.assert_allclose(boxes0, [[7.5, 19.5, 82, 16]])
    assert area0[0] == m.sum()


@pytest.mark.parametrize("seed", range(6))
def test_equals_the_per_blob_loop_on_random_masks(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = np.zeros((70, 90), np.uint8)
    for _ in range(12):  # rectangles of every shape, overlapping into blobs
        x, y = rng.integers(0, 80), rng.integers(0, 60)
        cv2.rectangle(m, (int(x), int(y)), (int(x + rng.integers(1, 25)),
                                            int(y + rng.integers(1, 30))), 1, -1)
    m = m.astype(bool)
    labels, ids, stats = label(m)
    for tau in (0.2, 0.5):
        boxes, src, area = cut_flat_wings(labels, ids, stats, tau)
        got = sorted(map(tuple, np.column_stack([boxes, area]).tolist()))
        np.testing.assert_allclose(np.array(got), np.array(oracle(m, tau)))
        assert len(src) == len(boxes)
        # blob by blob in the order asked, left to right within a blob; each part inside its
        # blob's box
        order = np.lexsort((boxes[:, 0], src))
        np.testing.assert_array_equal(order, np.arange(len(src)))
        s = stats[ids[src]]
        assert (boxes[:, 0] >= s[:, 0] - 0.5).all() and (boxes[:, 2] <= s[:, 2]).all()
        # the plain function the kernel is compiled from gives the same
        for a, b in zip(wing_parts.py_func(labels, ids.astype(np.intp), stats, tau),
                        (boxes, src, area), strict=True):
            np.testing.assert_array_equal(a, b)


def test_only_the_blobs_asked_for() -> None:
    m = np.zeros((60, 60), bool)
    walker(m, 5, 50)
    walker(m, 40, 50)
    labels, ids, stats = label(m)
    boxes, src, _ = cut_flat_wings(labels, ids[1:], stats, 0.3)
    np.testing.assert_allclose(boxes, [[39.5, 9.5, 12, 40]])
    assert (src == 0).all()
    empty = cut_flat_wings(labels, ids[:0], stats, 0.3)
    assert [a.shape[0] for a in empty] == [0, 0, 0]
