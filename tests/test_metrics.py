"""Metrics: agreement with motmetrics (its TUD example) and TrackEval; hand-computed HOTA."""

from __future__ import annotations

import contextlib
import io
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

import mvtrack.eval.hota as hota_mod
from mvtrack.eval.hota import hota
from mvtrack.eval.iou import iou_matrix
from mvtrack.eval.metrics import evaluate
from mvtrack.io.mot import MotTable

mm = pytest.importorskip("motmetrics")
TUD = Path(mm.__file__).parent / "data"
SEQS = ("TUD-Campus", "TUD-Stadtmitte")

# The values motmetrics' own test suite asserts for these two files
# (motmetrics/tests/test_metrics.py::test_motchallenge_files, motmetrics 1.4.0):
# idf1, idp, idr, recall, precision, GT ids, MT, PT, ML, FP, FN, IDSW, FM, MOTA, motp (1 - IoU).
MOTMETRICS_EXPECTED = {
    "TUD-Campus": [0.557659, 0.729730, 0.451253, 0.582173, 0.941441, 8, 1, 6, 1, 13, 150, 7, 7,
                   0.526462, 0.277201],
    "TUD-Stadtmitte": [0.644619, 0.819760, 0.531142, 0.608997, 0.939920, 10, 5, 4, 1, 45, 452, 7,
                       6, 0.564014, 0.345904],
}
OUR_KEYS = ["IDF1", "IDP", "IDR", "recall", "precision", "num_gt_ids", "MT", "PT", "ML", "FP",
            "FN", "IDSW", "FM", "MOTA"]


def _motmetrics_reference(seq: str) -> dict[str, float]:
    """motmetrics end to end on its own loader, as its test suite does, with a NumPy-2-safe IoU.

    This replicates ``motmetrics.utils.compare_to_groundtruth(gt, test, "iou", distth=0.5)``
    (which calls the removed ``np.asfarray``) using motmetrics' own ``boxiou``.
    """
    gt = mm.io.loadtxt(str(TUD / seq / "gt.txt"))
    dt = mm.io.loadtxt(str(TUD / seq / "test.txt"))
    fields = ["X", "Y", "Width", "Height"]
    acc = mm.MOTAccumulator()
    fgt = dict(iter(gt[fields].groupby("FrameId")))
    fdt = dict(iter(dt[fields].groupby("FrameId")))
    for fid in gt.index.union(dt.index).levels[0]:
        oids, hids = np.empty(0), np.empty(0)
        dists = np.empty((0, 0))
        if fid in fgt:
            oids = fgt[fid].index.get_level_values("Id")
        if fid in fdt:
            hids = fdt[fid].index.get_level_values("Id")
        if len(oids) and len(hids):
            a = fgt[fid].to_numpy(dtype=float)
            b = fdt[fid].to_numpy(dtype=float)
            d = 1.0 - mm.distances.boxiou(a[:, None], b[None, :])
            dists = np.where(d > 0.5, np.nan, d)
        else:
            dists = np.empty((len(oids), len(hids)))
        acc.update(oids, hids, dists, frameid=fid)
    names = ["idf1", "mota", "motp", "num_switches", "num_false_positives", "num_misses"]
    return mm.metrics.create().compute(acc, metrics=names, return_dataframe=False)


@pytest.mark.parametrize("seq", SEQS)
def test_tud_matches_values_asserted_by_motmetrics_tests(seq: str) -> None:
    ours = evaluate(TUD / seq / "gt.txt", TUD / seq / "test.txt", iou=0.5)
    expected = MOTMETRICS_EXPECTED[seq]
    got = [ours[k] for k in OUR_KEYS] + [1.0 - ours["MOTP"]]
    np.testing.assert_allclose(got, expected, atol=1e-6)


@pytest.mark.parametrize("seq", SEQS)
def test_tud_matches_motmetrics_reference_computation(seq: str) -> None:
    ref = _motmetrics_reference(seq)
    ours = evaluate(TUD / seq / "gt.txt", TUD / seq / "test.txt", iou=0.5, with_hota=False)
    assert ours["IDSW"] == ref["num_switches"]
    assert ours["FP"] == ref["num_false_positives"] and ours["FN"] == ref["num_misses"]
    assert ours["MOTA"] == pytest.approx(ref["mota"], abs=1e-12)
    assert ours["IDF1"] == pytest.approx(ref["idf1"], abs=1e-12)
    assert ours["MOTP"] == pytest.approx(1.0 - ref["motp"], abs=1e-12)


def test_hota_matches_trackeval_own_mot_pipeline_on_tud(tmp_path: Path) -> None:
    """Our data dict against TrackEval's MOTChallenge loader (MOT15 mode: no preprocessing)."""
    with contextlib.redirect_stdout(io.StringIO()):  # it prints about missing pycocotools
        trackeval = pytest.importorskip("trackeval")  # the package, where it is installed

    for seq in SEQS:
        (tmp_path / "gt" / seq / "gt").mkdir(parents=True)
        shutil.copy(TUD / seq / "gt.txt", tmp_path / "gt" / seq / "gt" / "gt.txt")
        (tmp_path / "tr" / "t" / "data").mkdir(parents=True, exist_ok=True)
        shutil.copy(TUD / seq / "test.txt", tmp_path / "tr" / "t" / "data" / f"{seq}.txt")
    quiet = {"PRINT_CONFIG": False}
    with contextlib.redirect_stdout(io.StringIO()):
        evaluator = trackeval.Evaluator({
            "USE_PARALLEL": False, "PRINT_RESULTS": False, "OUTPUT_SUMMARY": False,
            "OUTPUT_DETAILED": False, "PLOT_CURVES": False, "TIME_PROGRESS": False, **quiet,
        })
        dataset = trackeval.datasets.MotChallenge2DBox({
            "GT_FOLDER": str(tmp_path / "gt"), "TRACKERS_FOLDER": str(tmp_path / "tr"),
            "BENCHMARK": "MOT15", "SKIP_SPLIT_FOL": True, "TRACKERS_TO_EVAL": ["t"],
            "SEQ_INFO": {"TUD-Campus": 71, "TUD-Stadtmitte": 179}, **quiet,
        })
        res, _ = evaluator.evaluate([dataset], [trackeval.metrics.HOTA()])
    for seq in SEQS:
        ref = res["MotChallenge2DBox"]["t"][seq]["pedestrian"]["HOTA"]
        ours = evaluate(TUD / seq / "gt.txt", TUD / seq / "test.txt")
        for key in ("HOTA", "DetA", "AssA", "LocA"):
            assert ours[key] == pytest.approx(float(np.mean(ref[key])), abs=1e-12), (seq, key)


def _track(frames: list[int], ids: list[int], tlwh: np.ndarray) -> MotTable:
    k = len(frames)
    tlwh = np.broadcast_to(np.asarray(tlwh, float), (k, 4))
    return MotTable(frames, ids, tlwh, np.ones(k), np.full(k, -1), np.full(k, -1.0))


def test_identical_gt_and_prediction_score_one() -> None:
    rng = np.random.default_rng(3)
    frames = np.repeat(np.arange(20), 3)
    ids = np.tile([1, 2, 3], 20)
    tlwh = np.column_stack([rng.uniform(0, 500, (60, 2)), rng.uniform(5, 50, (60, 2))])
    gt = MotTable(frames, ids, tlwh, np.ones(60), np.ones(60), np.ones(60))
    pred = MotTable(frames, ids + 100, tlwh, np.ones(60), np.ones(60), np.ones(60))
    s = evaluate(gt, pred)
    for key in ("MOTA", "MOTP", "IDF1", "HOTA", "DetA", "AssA", "LocA"):
        assert s[key] == pytest.approx(1.0, abs=1e-9), key
    assert (s["IDSW"], s["FP"], s["FN"], s["MT"], s["ML"]) == (0, 0, 0, 3, 0)


def test_id_switch_halfway_gives_hand_computed_scores() -> None:
    # One GT track over 4 frames; the prediction is exact but changes ID after frame 1.
    box = [10, 10, 20, 40]
    gt = _track([0, 1, 2, 3], [1, 1, 1, 1], box)
    pred = _track([0, 1, 2, 3], [7, 7, 8, 8], box)
    s = evaluate(gt, pred)
    # CLEAR-MOT: one switch, MOTA = 1 - 1/4. Identity: best ID pairing covers 2 of 4 boxes on
    # each side, IDF1 = 2·2 / (4 + 4).
    assert s["IDSW"] == 1 and s["MOTA"] == pytest.approx(0.75)
    assert s["IDF1"] == pytest.approx(0.5)
    # HOTA: every box matched at every α (DetA = 1); each of the two (gt, pred) ID pairs has
    # TPA = 2, FNA = 2, FPA = 0 → A = 2/4, so AssA = 0.5, AssRe = 0.5, AssPr = 1, HOTA = √0.5.
    assert s["DetA"] == pytest.approx(1.0)
    assert s["AssA"] == pytest.approx(0.5)
    assert s["AssRe"] == pytest.approx(0.5) and s["AssPr"] == pytest.approx(1.0)
    assert s["HOTA"] == pytest.approx(np.sqrt(0.5))


def test_partial_overlap_counts_only_thresholds_below_its_iou() -> None:
    # Prediction overlaps the GT box with IoU 0.63 (same left/top/width, height 6.3 of 10).
    gt = _track([0, 1, 2], [1, 1, 1], [0, 0, 10, 10])
    pred = _track([0, 1, 2], [4, 4, 4], [0, 0, 10, 6.3])
    assert iou_matrix(gt.tlwh[:1], pred.tlwh[:1])[0, 0] == pytest.approx(0.63)
    # TrackEval's α grid is 0.05, 0.10, ..., 0.95: the 12 values up to 0.60 match.
    assert hota(gt, pred)["HOTA"] == pytest.approx(12 / 19)  # type: ignore[index]
    loose, strict = evaluate(gt, pred, iou=0.5), evaluate(gt, pred, iou=0.7)
    assert loose["MOTA"] == pytest.approx(1.0) and loose["MOTP"] == pytest.approx(0.63)
    assert (strict["FP"], strict["FN"]) == (3, 3) and strict["MOTA"] == pytest.approx(-1.0)


def test_iou_matrix_agrees_with_motmetrics_boxiou() -> None:
    rng = np.random.default_rng(4)
    a = np.column_stack([rng.uniform(0, 100, (30, 2)), rng.uniform(0, 40, (30, 2))])
    b = np.column_stack([rng.uniform(0, 100, (25, 2)), rng.uniform(0, 40, (25, 2))])
    a[0, 2] = 0.0  # a degenerate box
    ours = iou_matrix(a, b)
    ref = mm.distances.boxiou(a[:, None], b[None, :])
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    assert ours.shape == (30, 25) and (ours >= 0).all() and (ours <= 1).all()
    assert iou_matrix(np.zeros((0, 4)), b).shape == (0, 25)


def test_frames_with_only_one_side_count_as_misses_or_false_alarms() -> None:
    gt = _track([0, 1, 2], [1, 1, 1], [0, 0, 10, 10])
    pred = _track([0, 1, 5], [2, 2, 2], [0, 0, 10, 10])
    s = evaluate(gt, pred)
    assert (s["FN"], s["FP"], s["num_matches"]) == (1, 1, 2)
    assert s["num_frames"] == 6


def test_missing_trackeval_reports_hota_as_missing(monkeypatch: pytest.MonkeyPatch) -> None:
    hota_mod._import_hota.cache_clear()
    monkeypatch.setitem(sys.modules, "mvtrack._vendor.trackeval.metrics", None)
    try:
        gt = _track([0, 1], [1, 1], [0, 0, 10, 10])
        s = evaluate(gt, gt)
    finally:
        hota_mod._import_hota.cache_clear()
    assert s["HOTA"] is None and s["AssA"] is None
    assert s["MOTA"] == pytest.approx(1.0)
    assert len(s["notes"]) == 1 and "trackeval" in s["notes"][0]


def test_bad_iou_threshold_is_rejected() -> None:
    gt = _track([0], [1], [0, 0, 10, 10])
    with pytest.raises(ValueError, match="iou"):
        evaluate(gt, gt, iou=0.0)
