"""The part graph of a structured object: ``K`` parts joined by ``E`` adjacency edges."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mvtrack.filters.base import FloatArray

IntArray = NDArray[np.intp]

__all__ = ["PartGraph"]


@dataclass(frozen=True, eq=False)
class PartGraph:
    """Adjacency graph of the ``K`` parts of an object (Fig. 2 / Fig. 8 of paper 3).

    Parameters
    ----------
    n_parts : int
        Number of parts ``K`` (cells), numbered 0 … K−1.
    edges : array (E, 2) of int
        Adjacent pairs. Each pair is stored ordered, ``i < j`` (E3.5); the relation filter of
        edge ``e`` estimates ``m^{edges[e,1]} − m^{edges[e,0]}``. Use :meth:`from_edges` to build
        a graph from pairs in any orientation.
    """

    n_parts: int
    edges: IntArray

    def __post_init__(self) -> None:
        edges = np.asarray(self.edges, dtype=np.intp).reshape(-1, 2)
        if self.n_parts < 1:
            raise ValueError(f"n_parts must be >= 1, got {self.n_parts}")
        if edges.size and (edges.min() < 0 or edges.max() >= self.n_parts):
            raise ValueError(f"edges must index parts 0..{self.n_parts - 1}, got {edges.tolist()}")
        if np.any(edges[:, 0] >= edges[:, 1]):
            raise ValueError("edges must be ordered pairs i < j; use PartGraph.from_edges")
        if len({tuple(e) for e in edges.tolist()}) != len(edges):
            raise ValueError(f"duplicate edges in {edges.tolist()}")
        object.__setattr__(self, "edges", edges)

    @classmethod
    def from_edges(cls, n_parts: int, pairs: object) -> PartGraph:
        """Graph from adjacent pairs in any orientation; each is stored as (min, max)."""
        arr = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
        if np.any(arr[:, 0] == arr[:, 1]):
            raise ValueError(f"a part cannot be adjacent to itself: {arr.tolist()}")
        arr = np.sort(arr, axis=1)
        _, first = np.unique(arr, axis=0, return_index=True)
        return cls(n_parts, arr[np.sort(first)])

    @classmethod
    def chain(cls, n_parts: int) -> PartGraph:
        """The chain 0–1–2–…, e.g. head–torso–legs (Fig. 8 of paper 3)."""
        idx = np.arange(n_parts - 1)
        return cls(n_parts, np.stack([idx, idx + 1], axis=1))

    @property
    def n_edges(self) -> int:
        """Number of relations ``E``."""
        return int(self.edges.shape[0])

    @property
    def tail(self) -> FloatArray:
        """Incidence matrix (K, E): 1 where part k is the first (smaller) end of edge e."""
        out = np.zeros((self.n_parts, self.n_edges))
        out[self.edges[:, 0], np.arange(self.n_edges)] = 1.0
        return out

    @property
    def head(self) -> FloatArray:
        """Incidence matrix (K, E): 1 where part k is the second (larger) end of edge e."""
        out = np.zeros((self.n_parts, self.n_edges))
        out[self.edges[:, 1], np.arange(self.n_edges)] = 1.0
        return out

    @property
    def degree(self) -> IntArray:
        """N_j = |𝒩(j)|, the number of parts adjacent to each part (K,)."""
        return np.bincount(self.edges.ravel(), minlength=self.n_parts).astype(np.intp)

    def neighbours(self, j: int) -> list[int]:
        """Parts adjacent to part ``j``, ascending."""
        e = self.edges
        return sorted(e[e[:, 0] == j, 1].tolist() + e[e[:, 1] == j, 0].tolist())

    def filters_used_by(self, j: int, labels: list[str] | None = None) -> list[str]:
        """Names of the filters that enter part ``j``'s estimate in eq. (13): its own cell filter,
        the cell filters of its neighbours (through their measurements m_c^i) and the relation
        filters of its edges. Parts are named ``labels`` (default 1-based numbers, as in Fig. 2)."""
        names = labels or [str(k + 1) for k in range(self.n_parts)]
        cells = sorted([j, *self.neighbours(j)])
        rels = [e for e in self.edges.tolist() if j in e]
        return [f"KF{names[c]}" for c in cells] + [f"KF{names[a]}{names[b]}" for a, b in rels]
