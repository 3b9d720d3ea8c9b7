"""The candidate pairs and the chains of track pieces (mvtrack.fragments)."""

from __future__ import annotations

import numpy as np

from mvtrack.fragments import chain_heads, starts_between


def test_starts_between_equals_the_brute_force_pairs() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        t = int(rng.integers(0, 30))
        start = rng.integers(0, 100, t)
        first = rng.integers(0, 100, t)
        last = first + rng.integers(-3, 15, t)  # some windows empty
        a, b = starts_between(start, first, last)
        got = sorted(zip(a.tolist(), b.tolist(), strict=True))
        want = sorted((i, j) for i in range(t) for j in range(t)
                      if first[i] <= start[j] <= last[i])
        assert got == want
        assert np.all(np.diff(a) >= 0)  # by a


def test_chain_heads_follow_each_chain_to_its_first_piece() -> None:
    # 0 → 2 → 4 → 1, 3 alone, 5 → 6
    parent = np.array([0, 4, 0, 3, 2, 5, 5])
    assert chain_heads(parent).tolist() == [0, 0, 0, 3, 0, 5, 5]
    assert chain_heads(np.arange(4)).tolist() == [0, 1, 2, 3]
