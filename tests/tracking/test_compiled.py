"""The compiled frame step (mvtrack.tracking.compiled) gives the array step's tracks exactly."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.association import discs
from mvtrack.io.mot import read_detections
from mvtrack.tracking import Tracker, TrackerConfig, compiled, preset
from mvtrack.types import Detections

FIELDS = ("track_id", "state", "det_index", "measured_xy", "filtered_xy", "predicted_xy",
          "wh", "velocity")

MOT15 = {"TUD-Campus": 25.0, "TUD-Stadtmitte": 25.0, "ADL-Rundle-6": 30.0, "KITTI-17": 10.0}

#: settings the compiled step covers, off the default: each changes a branch of it
VARIANTS = [
    {},
    {"second_gate": None},
    {"recover_speed": None},
    {"size_gate": None},
    {"partial_tolerance": None},
    {"size_ref": None},
    {"size_weight": 0.0},
    {"low_birth_iou": None},
    {"score_high": None},
    {"low_tentative": True},
    {"confirm_hits": 1},
    {"output_tentative": True, "coast_output": None},
    {"frame_size": (640, 480)},
    {"relink_window": None},
]


def _counting(monkeypatch: pytest.MonkeyPatch, module: object, name: str) -> list[int]:
    """Count the calls of ``module.name`` (wrapped)."""
    calls = [0]
    real = getattr(module, name)

    def spy(*args, **kwargs):
        calls[0] += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, spy)
    return calls


def _run(config: TrackerConfig, frames: list[Detections], core: str) -> list:
    tracker = Tracker(config, core=core)
    return [tracker.step(d) for d in frames]


def _assert_same(a: list, b: list) -> None:
    for fa, fb in zip(a, b, strict=True):
        for f in FIELDS:
            # the same floating-point operations in the same order: equal, not close
            np.testing.assert_array_equal(getattr(fa, f), getattr(fb, f), err_msg=f)


def _scene(seed: int, n_obj: int = 14, frames: int = 60) -> list[Detections]:
    """People walking through one another in 640 × 480 with everything the stages meet:
    missed boxes, low-scored duplicates beside a person, clutter, lower-body boxes (partial
    views), boxes of another scale (the size gate), people who stop being detected and come
    back, frames without a box, a box given twice, raw scores on a DPM-like scale."""
    rng = np.random.default_rng(seed)
    pos = rng.uniform([40, 120], [600, 420], size=(n_obj, 2))
    vel = rng.normal(0, 2.5, size=(n_obj, 2))
    size = np.column_stack([rng.uniform(20, 70, n_obj), np.zeros(n_obj)])
    size[:, 1] = size[:, 0] * rng.uniform(2.0, 2.8, n_obj)
    out = []
    for k in range(frames):
        pos += vel + rng.normal(0, 0.8, size=pos.shape)
        xy, wh, sc = [], [], []
        for i in range(n_obj):
            if rng.random() < 0.15 or (i % 5 == 0 and 20 <= k < 26):
                continue  # missed (and a gap of six frames for every fifth person)
            w, h = size[i] * rng.uniform(0.92, 1.08)
            if rng.random() < 0.1:  # the lower body only: a partial view
                hp = h * rng.uniform(0.35, 0.6)
                xy.append(pos[i] + [rng.normal(0, 2), h / 2 - hp / 2])
                wh.append([w * 0.9, hp])
            elif rng.random() < 0.15:  # a box of another scale, near the size gate's factor
                f = rng.uniform(1.3, 1.7) ** rng.choice([-1, 1])
                xy.append(pos[i] + rng.normal(0, 1.5, 2))
                wh.append([w * f, h * f])
            else:
                xy.append(pos[i] + rng.normal(0, 1.5, 2))
                wh.append([w, h])
            sc.append(rng.uniform(10, 120))
            if rng.random() < 0.2:  # a low-scored second box on the same person
                xy.append(pos[i] + rng.normal(0, 6, 2))
                wh.append([w * 1.1, h * 1.05])
                sc.append(rng.uniform(-1, 8))
        for _ in range(rng.poisson(1.0)):  # clutter
            xy.append(rng.uniform([0, 0], [640, 480]))
            wh.append(rng.uniform([15, 30], [60, 150]))
            sc.append(rng.uniform(-1, 30))
        if k in (40, 41):  # frames without a box
            xy, wh, sc = [], [], []
        elif k == 45 and xy:  # a box given twice, exactly (ties in every cost)
            xy.append(xy[0])
            wh.append(wh[0])
            sc.append(sc[0])
        order = rng.permutation(len(xy))
        out.append(Detections(k, np.array(xy, float).reshape(-1, 2)[order],
                              np.array(wh, float).reshape(-1, 2)[order],
                              np.array(sc, float)[order]))
    return out


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), variant=st.sampled_from(VARIANTS),
       fps=st.sampled_from([10.0, 25.0, 30.0]))
def test_compiled_equals_array_step(seed: int, variant: dict, fps: float) -> None:
    config = preset("default", fps=fps, **variant)
    frames = _scene(seed)
    _assert_same(_run(config, frames, "numpy"), _run(config, frames, "auto"))


def test_every_stage_and_the_solver_are_exercised(monkeypatch: pytest.MonkeyPatch) -> None:
    """The scenes of the property test reach the compiled step, the assignment solver
    (conflicts) and the recovery stage; without that the equality above would say little."""
    frames = _scene(3, n_obj=20)
    config = preset("default", fps=25.0)
    steps = _counting(monkeypatch, compiled, "frame_step")
    auto = _run(config, frames, "auto")
    assert steps[0] == len(frames) - 1  # every frame but the first (no tracks yet)
    lsa = _counting(monkeypatch, discs, "linear_sum_assignment")
    from mvtrack.tracking import stages

    recover = _counting(monkeypatch, stages.Associator, "_recover")
    low = _counting(monkeypatch, stages.Associator, "_low_stage")
    _assert_same(_run(config, frames, "numpy"), auto)
    assert steps[0] == len(frames) - 1  # the array run did not use it
    assert lsa[0] >= 5 and recover[0] >= 5 and low[0] >= 5


def test_large_frames_take_the_array_step(monkeypatch: pytest.MonkeyPatch) -> None:
    """Above DENSE_LSA track × detection pairs the array step runs (sparse gating), and the
    tracks are the same as with it alone."""
    frames = _scene(5, n_obj=70, frames=12)
    config = preset("default", fps=25.0)
    steps = _counting(monkeypatch, compiled, "frame_step")
    auto = _run(config, frames, "auto")
    sizes = []
    tracker = Tracker(config, core="numpy")
    for d in frames:
        sizes.append(tracker.n_tracks * d.xy.shape[0])
        tracker.step(d)
    small = sum(1 for s in sizes if 0 < s <= discs.DENSE_LSA)
    assert small < len(frames) - 1 and steps[0] == small
    _assert_same(_run(config, frames, "numpy"), auto)


@pytest.mark.parametrize("override", [
    {"distance": "mahalanobis"},
    {"predictor": "kalman-ca"},
    {"assign": "greedy"},
    {"warmup": True},
    {"stopped_margin": 5.0},
])
def test_settings_it_does_not_cover_take_the_array_step(override: dict) -> None:
    config = preset("default", fps=25.0, **override)
    assert not compiled.covers(config, Tracker(config, core="numpy").predictor)
    assert Tracker(config)._compiled is None
    assert Tracker(preset("default", fps=25.0))._compiled is not None


def test_a_rescue_callback_takes_the_array_step(monkeypatch: pytest.MonkeyPatch) -> None:
    frames = _scene(7, frames=20)
    steps = _counting(monkeypatch, compiled, "frame_step")
    tracker = Tracker(preset("default", fps=25.0))
    for d in frames:
        tracker.step(d, rescue=lambda uids, xy, wh: (np.zeros(len(uids), bool), xy))
    assert steps[0] == 0


def test_without_numba_the_array_step_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(compiled, "njit", None)  # what the import leaves when numba is missing
    assert not compiled.available()
    frames = _scene(11, frames=15)
    tracker = Tracker(preset("default", fps=25.0))
    assert tracker._compiled is None
    _assert_same([tracker.step(d) for d in frames],
                 _run(preset("default", fps=25.0), frames, "numpy"))


def test_unknown_core_is_refused() -> None:
    with pytest.raises(ValueError, match="core must be 'auto' or 'numpy'"):
        Tracker(core="fast")


def test_mot15_sequences_identical(shared_dir) -> None:
    """Every output field of every frame of the four MOT15 development sequences."""
    for seq, fps in MOT15.items():
        frames = list(read_detections(shared_dir / "data" / "real" / seq / "det.txt"))
        config = preset("default", fps=fps)
        _assert_same(_run(config, frames, "numpy"), _run(config, frames, "auto"))
