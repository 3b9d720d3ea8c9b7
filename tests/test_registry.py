"""The registries of names: every registered name works, the CLI offers exactly these."""

from __future__ import annotations

import numpy as np
import pytest

from mvtrack import registry
from mvtrack.association import assign
from mvtrack.cli import main
from mvtrack.detection import DETECTORS, FrontEnd, make_detector
from mvtrack.types import Detections

#: the registered front ends with a background model (the others detect objects in each frame)
BACKGROUND = [n for n in registry.DETECTORS if issubclass(DETECTORS[n], FrontEnd)]


def test_the_registry_is_the_list_of_detectors() -> None:
    assert list(DETECTORS) == list(registry.DETECTORS)
    assert {"disturbance-map", "frame-diff", "mog2", "knn"} <= set(BACKGROUND)
    assert "hog" in registry.DETECTORS and "hog" not in BACKGROUND


@pytest.mark.parametrize("name", BACKGROUND)
def test_every_registered_background_model_is_built_by_name_and_detects(name: str) -> None:
    det = make_detector(name)
    assert isinstance(det, FrontEnd)
    rng = np.random.default_rng(0)
    road = np.full((60, 80, 3), 90.0)
    for _ in range(40):  # the empty road: every model learns it
        det((road + rng.normal(0, 2, road.shape)).astype(np.uint8))
    frame = road.copy()
    frame[20:30, 30:45] = 220
    dets = det((frame + rng.normal(0, 2, road.shape)).astype(np.uint8))
    assert len(dets) == 1 and np.abs(dets.xy[0] - (37.0, 24.5)).max() <= 1.0


@pytest.mark.parametrize("name", [n for n in registry.DETECTORS if n not in BACKGROUND])
def test_every_other_registered_detector_is_built_by_name_and_runs(name: str) -> None:
    det = make_detector(name)
    road = np.full((60, 80, 3), 90, np.uint8)  # smaller than HOG's 64x128 window
    dets = det(road, 7)
    assert isinstance(dets, Detections) and dets.frame == 7 and len(dets) == 0
    big = np.full((240, 320, 3), 90, np.uint8)
    assert len(det(big, 8)) == 0  # a plain wall is not a person


@pytest.mark.parametrize("rule", list(registry.ASSIGN_RULES))
def test_every_registered_rule_assigns(rule: str) -> None:
    # two tracks, two detections, a cross pair cheaper than one of the straight ones
    ti, dj, cost = np.array([0, 0, 1]), np.array([0, 1, 1]), np.array([1.0, 0.5, 2.0])
    a = assign(ti, dj, cost, 2, 2, rule)
    expected = {"nearest": [(0, 1), (1, 1)], "greedy": [(0, 1)], "optimal": [(0, 0), (1, 1)]}
    assert sorted(zip(a.track.tolist(), a.det.tolist(), strict=True)) == expected[rule]


def test_unknown_names_are_refused_with_the_registered_ones() -> None:
    with pytest.raises(
        ValueError, match="choose one of: disturbance-map, frame-diff, mog2, knn, hog"
    ):
        make_detector("yolo")
    with pytest.raises(ValueError, match="nearest, greedy, optimal"):
        assign(np.array([0]), np.array([0]), np.array([1.0]), 1, 1, "hungarian")


def test_help_texts_list_the_registered_names(capsys) -> None:
    assert main(["track", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"{registry.one_of(registry.DETECTORS, registry.DEFAULT_DETECTOR)}." in text
    assert f"{registry.one_of(registry.ASSIGN_RULES)}." in text
    assert registry.one_of({"a": 1, "b": 2, "c": 3}, "b") == "a, b (default) or c"
