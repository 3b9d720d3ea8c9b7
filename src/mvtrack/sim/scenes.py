"""Simulated scenes with ground truth held as arrays, by name (SPEC §5 X4, X5, X7, X8; a crowd).

The scenes by name (:data:`SCENES`, :func:`build`); each family has its own module, and its
builder is importable from here too:

* :func:`x4_nine_vehicles` (:mod:`mvtrack.sim.nine_vehicles`) — paper 1's synthetic 9
  vehicles (SPEC X4), exact formulas.
* :func:`x5_intersection` (:mod:`mvtrack.sim.intersection`) — the reconstructed 4-way
  intersection (SPEC X5).
* :func:`x7_crossing` (:mod:`mvtrack.sim.crossing`) — paper 2's two crossing point targets
  (SPEC X7).
* :func:`x8_splitting_group` (:mod:`mvtrack.sim.splitting_group`) — paper 2's group of three
  splitting behind a car (SPEC X8).
* :func:`crowd` (:mod:`mvtrack.sim.crowd`) — ``N`` constant-velocity targets for scale tests.

The :class:`Scene` they return, and the assembly of its rows, are in :mod:`mvtrack.sim.scene`;
the paths vehicles follow in :mod:`mvtrack.sim.paths`.
"""

from __future__ import annotations

from mvtrack.sim.crossing import x7_crossing
from mvtrack.sim.crowd import crowd
from mvtrack.sim.intersection import (
    X5_CENTRE,
    X5_COLORS,
    X5_LANE,
    X5_ROAD_HALF,
    X5_STOP,
    x5_intersection,
    x5_path,
)
from mvtrack.sim.nine_vehicles import X4_COLORS, x4_nine_vehicles, x9_path
from mvtrack.sim.paths import Path2D
from mvtrack.sim.scene import MOT_CLASS, VISIBLE_MIN, Scene, luminance
from mvtrack.sim.splitting_group import x8_splitting_group

__all__ = [
    "MOT_CLASS",
    "SCENES",
    "VISIBLE_MIN",
    "X4_COLORS",
    "X5_CENTRE",
    "X5_COLORS",
    "X5_LANE",
    "X5_ROAD_HALF",
    "X5_STOP",
    "Path2D",
    "Scene",
    "build",
    "crowd",
    "luminance",
    "x4_nine_vehicles",
    "x5_intersection",
    "x5_path",
    "x7_crossing",
    "x8_splitting_group",
    "x9_path",
]

#: Scene names accepted by :func:`build`.
SCENES = ("x4", "x5", "x7", "x8", "crowd")


def build(name: str, *, seed: int = 0, frames: int | None = None, n: int | None = None) -> Scene:
    """Build a scene by name (``x4``, ``x5``, ``x7``, ``x8``, ``crowd``).

    ``frames`` truncates a fixed-length scene (or sets the crowd's length, default 300);
    ``n`` is the crowd's number of targets (default 100) and is refused for other scenes.
    """
    if name not in SCENES:
        raise ValueError(f"unknown scene {name!r}; choose one of {', '.join(SCENES)}")
    if n is not None and name != "crowd":
        raise ValueError(f"--n applies only to the crowd scene, not {name}")
    if name == "crowd":
        return crowd(100 if n is None else n, frames=300 if frames is None else frames, seed=seed)
    scene = {
        "x4": lambda: x4_nine_vehicles(),
        "x5": lambda: x5_intersection(seed),
        "x7": lambda: x7_crossing(seed),
        "x8": lambda: x8_splitting_group(seed),
    }[name]()
    return scene if frames is None else scene.truncate(frames)
