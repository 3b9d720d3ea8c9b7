"""The structured Kalman filter as an object, and behind the tracker's predictor protocol."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from mvtrack.filters.base import BoolArray, FloatArray, check_xy, check_z_mask
from mvtrack.filters.structured.graph import PartGraph
from mvtrack.filters.structured.params import SKFParams
from mvtrack.filters.structured.state import SKFState, SKFTerms, add_part, init, predict
from mvtrack.filters.structured.update import update

__all__ = [
    "StructuredKalmanFilter",
    "StructuredPredictor",
    "StructuredPredictorState",
    "search_region",
]


def search_region(centres: FloatArray, wh: FloatArray, scale: float = 1.5) -> FloatArray:
    """Search box of each object (SPEC §3.3, E3.10).

    The minimum enclosing rectangle (MER) of the parts' last bounding boxes moved to their
    predicted centres, with its sides scaled by ``scale`` about its centre.

    Parameters
    ----------
    centres : (N, K, 2)
        Predicted part centres m_c^{j−}.
    wh : (N, K, 2)
        Last known box sizes of the parts (NaN rows are ignored).
    scale : float
        Side factor (1.5 in paper 3).

    Returns
    -------
    (N, 4)
        Boxes ``x0, y0, x1, y1``; NaN for an object with no usable part.
    """
    centres = np.asarray(centres, dtype=float)
    wh = np.asarray(wh, dtype=float)
    if centres.shape != wh.shape or centres.ndim != 3 or centres.shape[-1] != 2:
        raise ValueError(f"centres and wh must both be (N, K, 2); got {centres.shape}, {wh.shape}")
    if not scale > 0:
        raise ValueError(f"scale must be > 0, got {scale}")
    ok = np.all(np.isfinite(centres) & np.isfinite(wh), axis=-1, keepdims=True)
    lo = np.where(ok, centres - wh / 2.0, np.inf).min(axis=1)
    hi = np.where(ok, centres + wh / 2.0, -np.inf).max(axis=1)
    any_ok = ok[..., 0].any(axis=1)[:, None]
    lo, hi = np.where(any_ok, lo, np.nan), np.where(any_ok, hi, np.nan)
    mid, half = (lo + hi) / 2.0, (hi - lo) / 2.0 * scale
    box = np.concatenate([mid - half, mid + half], axis=1)
    return np.where(any_ok, box, np.nan)


@dataclass
class StructuredKalmanFilter:
    """A structured Kalman filter for objects sharing one part graph (thin wrapper).

    Examples
    --------
    >>> g = PartGraph.chain(3)                       # head–torso–legs
    >>> skf = StructuredKalmanFilter(g)
    >>> s = skf.init(np.array([[[20., 106.], [20., 127.], [20., 159.]]]))
    >>> s = skf.predict(s)
    >>> s, terms = skf.update(s, np.array([[[22., 106.], [22., 127.], [np.nan, np.nan]]]),
    ...                       np.array([[0.0, 0.0, 1.0]]))
    """

    graph: PartGraph
    params: SKFParams = field(default_factory=SKFParams)

    def init(self, z: FloatArray) -> SKFState:
        """See :func:`init`."""
        return init(self.params, self.graph, z)

    def predict(self, state: SKFState) -> SKFState:
        """See :func:`predict`."""
        return predict(self.params, state)

    def update(
        self, state: SKFState, z: FloatArray, alpha: FloatArray
    ) -> tuple[SKFState, SKFTerms]:
        """See :func:`update`."""
        return update(self.params, self.graph, state, z, alpha)

    def add_part(
        self, state: SKFState, xy: FloatArray, neighbours: list[int]
    ) -> tuple[StructuredKalmanFilter, SKFState]:
        """See :func:`add_part`; returns a new filter with the grown graph."""
        graph, new = add_part(self.params, self.graph, state, xy, neighbours)
        return dataclasses.replace(self, graph=graph), new


@dataclass
class StructuredPredictorState:
    """Per-track state of :class:`StructuredPredictor` (leading dimension = tracks).

    ``xc, Pc, xr, Pr`` as in :class:`SKFState`; ``wh`` (N, K, 2) the parts' last box sizes
    (for :meth:`StructuredPredictor.search_region`), NaN when unknown.
    """

    xc: FloatArray
    Pc: FloatArray
    xr: FloatArray
    Pr: FloatArray
    wh: FloatArray

    @property
    def skf(self) -> SKFState:
        """The underlying :class:`SKFState` (views)."""
        return SKFState(self.xc, self.Pc, self.xr, self.Pr)


@dataclass(frozen=True)
class StructuredPredictor:
    """The SKF behind the tracker's :class:`~mvtrack.filters.base.Predictor` protocol.

    Each track is an object with ``K`` parts on a fixed graph (default a vertical chain of
    three, head–torso–legs). The tracker sees whole-object positions: the object position is the
    **mean of its part positions**, and its covariance that of the mean of the cells
    (Σ_j P_j / K², cross-covariances ignored).

    Two ways to feed it:

    - :meth:`update` (the protocol): a whole-object measurement ``z`` (N, 2) is read as the
      translation of the rigid part layout — part j is measured at z + (m_c^{j−} − mean m_c^{−}),
      all with α = 0 — and rows with ``mask`` False coast (α = 1 for every part). This keeps the
      tracker working with plain blob detections; it is then an ordinary Kalman filter per part.
    - :meth:`update_parts`: per-part centroids ``(N, K, 2)`` and occlusion degrees ``(N, K)``
      from :mod:`mvtrack.detection.parts`, which is where the structure pays off: a hidden part
      follows its neighbours through the relation filters (eq. (13) of paper 3).

    :meth:`init` places the parts at ``xy + offsets`` (``offsets`` (K, 2), default a vertical
    head/torso/legs layout of a ~70 px tall person) unless :meth:`init_parts` is used.

    ``r``, ``q`` and ``vel_var`` (the keywords the tracker passes to every predictor) override
    ``params.r_cell``, ``params.q`` and ``params.p0_vel``.
    """

    name: str = "structured"
    params: SKFParams = field(default_factory=SKFParams)
    graph: PartGraph = field(default_factory=lambda: PartGraph.chain(3))
    offsets: FloatArray = field(
        default_factory=lambda: np.array([[0.0, -21.0], [0.0, 0.0], [0.0, 32.0]])
    )
    r: float | None = None
    q: float | None = None
    vel_var: float | None = None

    def __post_init__(self) -> None:
        off = np.asarray(self.offsets, dtype=float)
        if off.shape != (self.graph.n_parts, 2):
            raise ValueError(f"offsets must have shape ({self.graph.n_parts}, 2), got {off.shape}")
        object.__setattr__(self, "offsets", off - off.mean(axis=0))
        # the tracker's common keywords: r (px²), q, vel_var (initial velocity variance)
        changes = {
            name: value
            for name, value in (("r_cell", self.r), ("q", self.q), ("p0_vel", self.vel_var))
            if value is not None
        }
        if changes:
            object.__setattr__(self, "params", dataclasses.replace(self.params, **changes))

    def init_parts(self, z: FloatArray, wh: FloatArray | None = None) -> StructuredPredictorState:
        """State for new tracks from part measurements ``z`` (K, parts, 2)."""
        s = init(self.params, self.graph, z)
        size = np.full((*s.xc.shape[:2], 2), np.nan) if wh is None else np.asarray(wh, float)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, size)

    def init(self, xy: FloatArray) -> StructuredPredictorState:
        """State of new tracks first measured at ``xy`` (K, 2), parts at ``xy + offsets``."""
        xy = check_xy("xy", xy)
        return self.init_parts(xy[:, None, :] + self.offsets[None])

    def predict(self, state: StructuredPredictorState) -> StructuredPredictorState:
        """Eqs. (9)–(12) for every track."""
        s = predict(self.params, state.skf)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, state.wh)

    def update_parts(
        self,
        state: StructuredPredictorState,
        z: FloatArray,
        alpha: FloatArray,
        wh: FloatArray | None = None,
    ) -> StructuredPredictorState:
        """Eqs. (13)–(15) with part centroids ``z`` (N, K, 2) and occlusion degrees (N, K)."""
        s, _ = update(self.params, self.graph, state.skf, z, alpha)
        size = state.wh
        if wh is not None:
            wh = np.asarray(wh, dtype=float)
            size = np.where(np.all(np.isfinite(wh), axis=-1, keepdims=True), wh, state.wh)
        return StructuredPredictorState(s.xc, s.Pc, s.xr, s.Pr, size)

    def update(
        self, state: StructuredPredictorState, z: FloatArray, mask: BoolArray
    ) -> StructuredPredictorState:
        """Whole-object update: ``z`` (N, 2) moves the rigid part layout; masked rows coast."""
        z, ok = check_z_mask(z, mask, state.xc.shape[0])
        pos = state.xc[..., :2]
        zp = z[:, None, :] + (pos - pos.mean(axis=1, keepdims=True))
        zp = np.where(ok[:, None, None], zp, np.nan)
        alpha = np.where(ok[:, None], 0.0, 1.0) * np.ones(pos.shape[:2])
        return self.update_parts(state, zp, alpha)

    def position(self, state: StructuredPredictorState) -> FloatArray:
        """Object position = mean of the part positions (N, 2)."""
        return state.xc[..., :2].mean(axis=1)

    def velocity(self, state: StructuredPredictorState) -> FloatArray:
        """Mean of the part velocities (N, 2)."""
        return state.xc[..., 2:4].mean(axis=1)

    def position_cov(self, state: StructuredPredictorState) -> FloatArray:
        """Covariance of the mean part position, Σ_j P_j[:2, :2] / K² (N, 2, 2)."""
        K = state.xc.shape[1]
        return state.Pc[..., :2, :2].sum(axis=1) / float(K * K)

    def innovation_cov(self, state: StructuredPredictorState) -> FloatArray:
        """S = P̄ + R_c / K for the mean of K part measurements (N, 2, 2)."""
        K = state.xc.shape[1]
        return self.position_cov(state) + self.params.R_cell / K

    def part_positions(self, state: StructuredPredictorState) -> FloatArray:
        """Part positions (N, K, 2)."""
        return state.xc[..., :2]

    def search_region(self, state: StructuredPredictorState, scale: float = 1.5) -> FloatArray:
        """Search boxes (N, 4) from the predicted parts and their last sizes (E3.10)."""
        return search_region(state.xc[..., :2], state.wh, scale)
