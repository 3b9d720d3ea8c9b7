"""Reproduced experiments of the three papers (SPEC §5, X1-X9).

Each experiment is a module with ``run(*, runs: int | None, seed: int) -> Report``;
:func:`mvtrack.experiments.report.write_report` writes its JSON, Markdown table and plots.
``runs=None`` means the experiment's own default (the paper's number of runs).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from mvtrack.experiments.report import Report

#: experiment name (as typed on the command line) -> module under mvtrack.experiments
EXPERIMENTS: dict[str, str] = {
    "predictors": "predictors",  # X1, paper 1 Figs. 5-8
    "complexity": "complexity",  # X2, paper 1 Table 1
    "timing": "timing",  # X3, paper 1 Table 2
    "coupled-gate": "coupled_gate",  # X6, paper 2 Fig. 1
    "crossing": "crossing",  # X7, paper 2 Fig. 2
    "synthetic-traffic": "synthetic_traffic",  # X4, paper 1 Figs. 9-10
    "intersection": "intersection",  # X5, paper 1 Figs. 11-13
    "splitting-group": "splitting_group",  # X8, paper 2 Fig. 4
    "occlusion": "occlusion",  # X9, paper 3 Figs. 9-11
}


def get(name: str) -> Callable[..., Report]:
    """The ``run`` function of experiment ``name``.

    Raises
    ------
    ValueError
        If ``name`` is not an experiment.
    """
    if name not in EXPERIMENTS:
        known = ", ".join(EXPERIMENTS)
        raise ValueError(f"unknown experiment {name!r}; choose one of: {known}")
    module = importlib.import_module(f"mvtrack.experiments.{EXPERIMENTS[name]}")
    return module.run  # type: ignore[no-any-return]
