"""The total order of gated pairs that every assignment rule breaks ties by.

Pairs are ordered by (cost, track row, detection row); :func:`rank_pairs` gives each pair its
position, :func:`best_of` the best pair of each track or detection, :func:`first_per_group`
the first element of each run of a sorted array.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

__all__ = ["best_of", "first_per_group", "rank_pairs"]


def first_per_group(group: IntArray) -> NDArray[np.bool_]:
    """For a sorted ``group`` array, True at the first element of each run."""
    first = np.ones(group.shape[0], dtype=bool)
    first[1:] = group[1:] != group[:-1]
    return first


def rank_pairs(ti: IntArray, dj: IntArray, cost: FloatArray) -> IntArray:
    """Position of every pair in the total order (cost, track row, detection row)."""
    order = np.argsort(cost, kind="stable")
    sc = cost[order]
    if sc.size > 1 and np.any(sc[1:] == sc[:-1]):  # ties: break them by (track, detection)
        order = np.lexsort((dj, ti, cost))
    rank = np.empty(cost.shape[0], dtype=np.intp)
    rank[order] = np.arange(cost.shape[0])
    return rank


def best_of(group: IntArray, rank: IntArray, size: int) -> IntArray:
    """(size,) smallest rank of each group (the largest intp where a group has no pair)."""
    best = np.full(size, np.iinfo(np.intp).max, dtype=np.intp)
    np.minimum.at(best, group, rank)
    return best
