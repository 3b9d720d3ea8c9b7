"""The structured Kalman filter (SKF) of paper 3 (SPEC §3), batched over objects and parts.

An object is a set of ``K`` parts (regions of one colour, e.g. head, torso, legs) joined by an
adjacency graph with ``E`` edges (:class:`PartGraph`). Every part has a *cell* Kalman filter on
its centre m_c^j; every adjacent pair (i, j), stored with i < j, has a *relation* Kalman filter on
the offset m_r^{ij} = m^j − m^i (eq. (5) of paper 3, E3.5). When a part is occluded (its
occlusion degree α^j of eq. (16) is high) its update leans on the measurements of its neighbours
carried over by the relation filters:

.. math::

    s_c^{j*} = s_c^{j-} + (1-α^j) K_c^j (m_c^j - m_c^{j-})
             + \\frac{α^j}{N_j} \\sum_{i∈\\mathcal N(j)} (1-α^i) K_c^j (\\tilde m^{j|i} - m_c^{j-})
    \\qquad (13)

    s_r^{ij*} = s_r^{ij-} + K_r^{ij} (m_r^{ij} - m_r^{ij-}) \\qquad (14)

    m_r^{ij} = \\{(1-α^j) m_c^j - (1-α^i) m_c^i\\} + \\{α^j m_c^{j-} - α^i m_c^{i-}\\} \\qquad (15)

with the readings of SPEC §4: the inner weight is the neighbour's (1 − α^i) (E3.2); the inferred
measurement is m̃^{j|i} = m_c^i + m_r^{ij−} from the relation *prior* (E3.4; option
``inferred="measurement"`` uses the relation measurement of (15), the literal (7)); the sign of
the relation follows its orientation (E3.5: j from i adds, i from j subtracts); the state is 6-D
constant acceleration with Δt²/2 (E3.7; option ``model="cv"``, 4-D, E3.6); the covariance follows
the standard Riccati recursion, independent of α (E3.9).

All state lives in arrays: cells ``(N, K, n)``, relations ``(N, E, n)`` for ``N`` objects that
share one part graph. The sum over neighbours in (13) is a product with the graph's incidence
matrices; there is no Python loop over objects or parts in :func:`predict` / :func:`update`.

Objects whose parts are missing in a frame get α = 1 for those parts (SPEC §3.3 "No match") and
NaN measurements; their (1 − α) terms are dropped.

Where we go beyond paper 3 (each documented on the implementing line):

- a relation with an unmatched end gets no update (with α^j = 1, (15) would measure the offset
  by the part's own prediction) and its derivatives decay by ``relation_damping`` per frame,
  so a part hidden for many frames keeps a bounded offset; a relation whose ends are matched
  decays by ``relation_damping ** α`` (``damping_by="alpha"``), α of its more occluded end,
  since (15) measures it by that end's prediction in proportion to α;
- a filter that receives no information at all keeps its prior covariance (E3.9 otherwise);
- options ``q_rel`` (relation process noise, default Q_r = 0.01·Q_c, E3.12: the parts of one
  body keep their relative positions far more steadily than the body moves; with Q_r = Q_c the
  CA relations of the X9 scene learn the legs' swing and extrapolate it while the legs are
  hidden, see the ``occlusion`` experiment) and ``relation_noise="occlusion"`` (R_r scaled by
  1/((1 − α^i)(1 − α^j))), and ``order="cells-first"`` ((13) before (15), which then blends
  the cells' posteriors instead of their priors; not the specification's order).

For the tracker, :class:`StructuredPredictor` (name ``structured``, built by
``mvtrack.filters.predictors.make_predictor("structured")``) wraps the SKF behind the
:class:`~mvtrack.filters.base.Predictor` protocol: the object position is the mean of its parts;
whole-object detections move the rigid part layout, and per-part measurements with α go through
:meth:`StructuredPredictor.update_parts`.

Cells and relations are batches of the one linear Kalman filter of
:mod:`mvtrack.filters.kalman` (its time update, gain, Joseph-form covariance and masked
update). Modules: :mod:`~.graph` (the part graph), :mod:`~.params` (the parameters and model
matrices), :mod:`~.state` (start, eqs. (9)–(12), new parts), :mod:`~.update` (eqs. (13)–(15))
and :mod:`~.predictor` (the filter object and the tracker's predictor).
"""

from __future__ import annotations

from mvtrack.filters.structured.graph import PartGraph
from mvtrack.filters.structured.params import SKFParams
from mvtrack.filters.structured.predictor import (
    StructuredKalmanFilter,
    StructuredPredictor,
    StructuredPredictorState,
    search_region,
)
from mvtrack.filters.structured.state import SKFState, SKFTerms, add_part, init, predict
from mvtrack.filters.structured.update import inferred_measurements, relation_measurement, update

__all__ = [
    "PartGraph",
    "SKFParams",
    "SKFState",
    "SKFTerms",
    "StructuredKalmanFilter",
    "StructuredPredictor",
    "StructuredPredictorState",
    "add_part",
    "inferred_measurements",
    "init",
    "predict",
    "relation_measurement",
    "search_region",
    "update",
]
