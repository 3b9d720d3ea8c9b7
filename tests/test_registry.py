"""The registries of names: every registered name works, the CLI offers exactly these."""

from __future__ import annotations

import re

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


@pytest.mark.parametrize("name", list(registry.PREDICTORS))
def test_every_registered_predictor_is_built_by_name_and_follows_a_target(name: str) -> None:
    from mvtrack.filters.predictors import PREDICTORS, make_predictor

    assert PREDICTORS == tuple(registry.PREDICTORS)
    predictor = make_predictor(name)
    assert isinstance(predictor, registry.load(registry.PREDICTORS[name]))
    truth = np.array([[10.0, 20.0], [200.0, 50.0]]) + np.arange(12)[:, None, None] * [2.0, -1.0]
    state = predictor.init(truth[0])
    for k in range(1, 12):
        state = predictor.predict(state)
        state = predictor.update(state, truth[k], np.ones(2, dtype=bool))
    # a target moving at 2 px/frame to the right and 1 px/frame up: after 11 updates every
    # predictor places it within a pixel of the next position
    ahead = predictor.position(predictor.predict(state))
    np.testing.assert_allclose(ahead, truth[11] + [2.0, -1.0], atol=1.0)
    with pytest.raises(ValueError, match="bad parameters for predictor"):
        make_predictor(name, no_such_parameter=1.0)


def test_the_distance_registry_is_the_one_table_of_default_gates() -> None:
    from mvtrack.association import DISTANCES, default_gate, resolve_gate
    from mvtrack.tracking import Tracker, preset

    assert list(DISTANCES) == list(registry.DISTANCES)
    assert registry.default_gate("euclidean") == 100.0  # a 10 px circle
    assert registry.default_gate("iou") == 0.7
    for name, choice in registry.DISTANCES.items():
        assert DISTANCES[name].gate == default_gate(name) == choice.gate
        assert resolve_gate(name) == choice.gate and resolve_gate(name, 2.5) == 2.5
        # what track-detections runs for --distance NAME without --gate: the table's gate,
        # its box_gate where it has one (euclidean: 9.21 on the distance in box sizes)
        config = preset("default", fps=30.0, distance=name)
        assert config.gate is None
        tracker_default = choice.gate if choice.box_gate is None else choice.box_gate
        assert Tracker(config).threshold == tracker_default
        assert (Tracker(config)._box_var > 0) == (choice.box_gate is not None)
    assert registry.DISTANCES["euclidean"].box_gate == 9.21
    assert [n for n, c in registry.DISTANCES.items() if c.box_gate is not None] == ["euclidean"]
    assert preset("default").gate is None  # the default preset takes the table's too
    with pytest.raises(ValueError, match="choose one of: euclidean, uncoupled"):
        registry.default_gate("cosine")


def test_gate_help_gives_every_default_gate(capsys) -> None:
    from mvtrack.cli._options import GATE_HELP

    assert GATE_HELP == registry.gate_help()
    for name, choice in registry.DISTANCES.items():
        assert name in GATE_HELP
        if choice.box_gate is None:
            assert f"{choice.gate:g} ({choice.unit})" in GATE_HELP
    # the tracker's Euclidean default is in box sizes; a gate given is px² (paper 1's 20 px)
    assert "euclidean 9.21 (χ² in box sizes)" in GATE_HELP
    assert "100 (px²)" not in GATE_HELP and "'20px'" in GATE_HELP
    assert main(["track-detections", "--help"]) == 0
    # the help is wrapped to the terminal, also after the hyphen of a name (kalman-⏎coupled)
    text = re.sub(r"-\s+", "-", " ".join(capsys.readouterr().out.split()))
    assert f"{registry.one_of(registry.PREDICTORS)}." in text
    assert f"{registry.one_of(registry.DISTANCES)}." in text


def test_cli_refuses_unregistered_predictors_and_distances(tmp_path, capsys) -> None:
    det = tmp_path / "d.txt"
    det.write_text("1,-1,10,10,5,5,1,-1,-1,-1\n")
    for option, value, names in (
        ("--predictor", "kalman-xyz", registry.PREDICTORS),
        ("--distance", "cosine", registry.DISTANCES),
    ):
        assert main(["track-detections", str(det), "--out", str(tmp_path), option, value]) == 2
        err = capsys.readouterr().err
        assert value in err and ", ".join(names) in err


def test_naming_the_default_distance_gives_byte_identical_results(tmp_path) -> None:
    """``--distance mahalanobis`` is the default distance named, ``--gate 9.21`` its default
    gate given: the same gate, the same file; ``--distance euclidean`` is another tracker."""
    from mvtrack.io.mot import write_detections

    rng = np.random.default_rng(4)
    start = rng.uniform(0, 300, size=(12, 2))
    vel = rng.normal(0, 3, size=(12, 2))
    frames = []
    for k in range(40):
        xy = start + k * vel + rng.normal(0, 1.5, size=start.shape)
        keep = np.flatnonzero(rng.random(len(xy)) > 0.1)
        frames.append(Detections(k, xy[keep], np.full((keep.size, 2), 30.0),
                                 score=rng.uniform(0.1, 1.0, keep.size)))
    det = tmp_path / "d.txt"
    write_detections(det, frames)
    outs = []
    for extra in ([], ["--distance", "mahalanobis"], ["--gate", "9.21"],
                  ["--distance", "euclidean"]):
        out = tmp_path / f"o{len(outs)}"
        assert main(["track-detections", str(det), "--out", str(out), *extra]) == 0
        outs.append((out / "d.txt").read_bytes())
    assert outs[0] == outs[1] == outs[2] and len(outs[0].splitlines()) > 100
    assert outs[3] != outs[0]  # the options reach the tracker: another distance, other rows
