"""X9 (paper 3, Figs. 9–11): the occlusion scene and the SKF-vs-independent-KFs experiment."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtrack.experiments import get
from mvtrack.experiments.occlusion import measurements_from_labels, run_independent, run_skf
from mvtrack.experiments.report import write_report
from mvtrack.filters.structured import SKFParams
from mvtrack.sim.occlusion import render_occlusion_scene


@pytest.fixture(scope="module")
def scene():
    return render_occlusion_scene(seed=0)


def test_scene_hides_the_legs_exactly_as_specified(scene) -> None:
    area = np.stack([(scene.labels == k).sum(axis=(1, 2)) for k in (1, 2, 3)], axis=1)
    assert scene.frames.shape == (150, 240, 320, 3)
    assert np.all(area[:146, 1] == 16 * 30)  # torso never occluded (it leaves the image at the end)
    assert area[0, 2] == 14 * 34
    hidden = np.flatnonzero(area[:, 2] == 0).tolist()
    partly = np.flatnonzero((area[:146, 2] > 0) & (area[:146, 2] < 14 * 34)).tolist()
    assert hidden == [125, 126, 127]
    assert partly[0] == 118 and partly[-1] == 134
    np.testing.assert_allclose(scene.centres[126, 2], [272.0, 159.0])
    np.testing.assert_allclose(scene.centres[:, 1, 0], 20 + 2 * np.arange(150))


def test_visible_centroids_are_exact_when_unoccluded(scene) -> None:
    meas = measurements_from_labels(scene)
    # pixel-centre inclusion: full boxes are measured at their true centre (to ½ px)
    err = np.abs(meas.z[:110, 1:] - scene.centres[:110, 1:])
    assert err.max() <= 0.5 + 1e-9
    assert np.all(np.isnan(meas.z[125:128, 2]))
    assert np.all(meas.alpha[125:129, 2] == 1.0)  # no match, then no previous features
    assert meas.alpha[100:117, 2].max() < 0.1  # unoccluded legs: features steady
    assert meas.alpha[118:125, 2].min() > 0.5  # shrinking visible area


def test_skf_cv_option_follows_the_hidden_legs_better_than_independent_kfs(scene) -> None:
    meas = measurements_from_labels(scene)
    params = SKFParams(model="cv")
    skf = run_skf(meas, params)
    base = run_independent(meas, params)
    e_skf = np.linalg.norm(skf.prior[115:141, 2] - scene.centres[115:141, 2], axis=1)
    e_base = np.linalg.norm(base[115:141, 2] - scene.centres[115:141, 2], axis=1)
    assert e_skf.max() < 7.0 and e_skf.max() < e_base.max()
    # while the legs are fully hidden the 3rd term of (13) carries the update
    assert np.all(skf.own[125:128, 2] == 0.0) and np.all(skf.neighbours[126:128, 2] > 0.0)


@pytest.mark.slow
def test_occlusion_experiment_report(tmp_path) -> None:
    report = get("occlusion")(runs=1, seed=0)
    fig = report.figures
    for key in (
        "skf_max_err",
        "skf_rms_err",
        "baseline_max_err",
        "baseline_rms_err",
        "alpha_peak_frame",
    ):
        assert key in fig
    assert 125 <= fig["alpha_peak_frame"] <= 128 and 126 in fig["alpha_peak_frames"]
    assert fig["paper"]["alpha_peak_frame"] == 126
    assert fig["segmentation_parts_found"] == 3
    assert fig["part3_never_lost"]
    # golden figures of seed 0 (SPEC default CA fails the [R] target; the CV option meets it)
    assert fig["skf_max_err"] == pytest.approx(30.98, abs=0.5)
    assert fig["baseline_max_err"] == pytest.approx(13.65, abs=0.5)
    assert not fig["target_met"]
    cv = fig["variants"]["cv (E3.6 option)"]
    assert cv["target_met"] and cv["skf_max_err"] == pytest.approx(3.39, abs=0.3)
    seg = fig["variants"]["segmentation, cv"]
    assert seg["skf_max_err"] == pytest.approx(cv["skf_max_err"], abs=0.5)
    paths = write_report(report, tmp_path)
    assert {p.name for p in paths} >= {"occlusion.json", "occlusion.md", "occlusion_fig9_alpha.png"}
    assert json.loads((tmp_path / "occlusion.json").read_text())["alpha_peak_frame"] == 126.5
