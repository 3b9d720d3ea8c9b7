"""Metrics against their references: motmetrics (its TUD example, its accumulator, peerbench's
scoring script), TrackEval (its MOT15 and MOT17 pipelines), and hand-computed cases."""

from __future__ import annotations

import contextlib
import importlib.util
import io
import shutil
import sys
import tracemalloc
from pathlib import Path
from types import ModuleType
from typing import Any

import motmetrics as mm
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtrack.eval.iou import iou_matrix, overlapping_pairs
from mvtrack.eval.metrics import evaluate, score_sequence
from mvtrack.io.mot import MotTable, read_tracks, write_mot, write_results

TUD = Path(mm.__file__).parent / "data"
SEQS = ("TUD-Campus", "TUD-Stadtmitte")
REAL = ("TUD-Campus", "TUD-Stadtmitte", "ADL-Rundle-6", "KITTI-17")

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

#: motmetrics metric → our key, compared exactly (==).
EXACT = {
    "mota": "MOTA", "idf1": "IDF1", "idp": "IDP", "idr": "IDR", "recall": "recall",
    "precision": "precision", "num_switches": "IDSW", "num_false_positives": "FP",
    "num_misses": "FN", "num_objects": "num_gt_dets", "num_predictions": "num_pred_dets",
    "num_unique_objects": "num_gt_ids", "mostly_tracked": "MT", "partially_tracked": "PT",
    "mostly_lost": "ML", "num_fragmentations": "FM", "num_matches": "num_matches",
}


# --------------------------------------------------------------------------- references


def _motmetrics_direct(gt: MotTable, pred: MotTable, iou: float = 0.5) -> dict[str, Any]:
    """motmetrics' accumulator fed frame by frame with its own ``boxiou`` (NumPy-2 safe).

    Every frame 1 … N is visited, rows in file order, distance ``1 - IoU`` and NaN below
    ``iou``: the rule of ``compare_to_groundtruth(gt, test, "iou", distth=1 - iou)``.
    """
    n = max(gt.num_frames, pred.num_frames)
    acc = mm.MOTAccumulator(auto_id=True)
    for f in range(n):
        g, p = np.flatnonzero(gt.frame == f), np.flatnonzero(pred.frame == f)
        d = 1.0 - mm.distances.boxiou(gt.tlwh[g][:, None], pred.tlwh[p][None, :])
        d = np.where(d > 1.0 - iou, np.nan, d).reshape(g.size, p.size)
        acc.update(gt.id[g].tolist(), pred.id[p].tolist(), d)
    names = [*EXACT, "motp", "num_frames"]
    return mm.metrics.create().compute(acc, metrics=names, return_dataframe=False)


def _load(name: str, path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _peerbench(shared: Path, gt: Path, res: Path) -> dict[str, Any]:
    """peerbench's own reading and scoring of a results file (run_peers.py, metrics.py)."""
    root = shared / "peerbench"
    sys.path.insert(0, str(root))
    try:
        rp = _load("peerbench_run_peers", root / "run_peers.py")
    finally:
        sys.path.remove(str(root))
    n = max(rp.last_frame(str(gt)), rp.last_frame(str(res)))
    frames = [rp.Frame(dets=np.empty((0, 5)), gt_ids=i, gt_boxes=b)
              for i, b in rp.read_gt(str(gt), n)]
    outs, _ = rp.read_results(str(res), n)
    return rp.metrics.evaluate(frames, outs, "iou")


def _trackeval(tmp: Path, gts: dict[str, Path], results: dict[str, Path], benchmark: str
               ) -> dict[str, Any]:
    """TrackEval's MotChallenge2DBox pipeline (HOTA, CLEAR, Identity) on files we copy in.

    With ``benchmark="MOT17"`` every 0-marked row becomes a distractor (class 8) and the
    others pedestrians (class 1), so TrackEval's preprocessing removes the predictions matched
    to 0-marked rows: the ``distractor`` rule.
    """
    trackeval = pytest.importorskip("trackeval")
    info = {}
    for seq, gt in gts.items():
        (tmp / "gt" / seq / "gt").mkdir(parents=True)
        rows = read_tracks(gt, "gt").to_rows()
        if benchmark == "MOT17":
            rows[:, 7] = np.where(rows[:, 6] == 0, 8, 1)
            rows[:, 8] = 1.0
        np.savetxt(tmp / "gt" / seq / "gt" / "gt.txt", rows[:, :9], delimiter=",", fmt="%.17g")
        (tmp / "tr" / "t" / "data").mkdir(parents=True, exist_ok=True)
        shutil.copy(results[seq], tmp / "tr" / "t" / "data" / f"{seq}.txt")
        info[seq] = int(max(rows[:, 0].max(), read_tracks(results[seq]).num_frames))
    quiet = {"PRINT_CONFIG": False}
    with contextlib.redirect_stdout(io.StringIO()):
        evaluator = trackeval.Evaluator({
            "USE_PARALLEL": False, "PRINT_RESULTS": False, "OUTPUT_SUMMARY": False,
            "OUTPUT_DETAILED": False, "PLOT_CURVES": False, "TIME_PROGRESS": False, **quiet,
        })
        dataset = trackeval.datasets.MotChallenge2DBox({
            "GT_FOLDER": str(tmp / "gt"), "TRACKERS_FOLDER": str(tmp / "tr"),
            "BENCHMARK": benchmark, "SKIP_SPLIT_FOL": True, "TRACKERS_TO_EVAL": ["t"],
            "SEQ_INFO": info, **quiet,
        })
        metrics = [trackeval.metrics.HOTA(), trackeval.metrics.Identity(),
                   trackeval.metrics.CLEAR()]
        res, _ = evaluator.evaluate([dataset], metrics)
    return {seq: r["pedestrian"] for seq, r in res["MotChallenge2DBox"]["t"].items()}


# --------------------------------------------------------------------------- results to score


def perturbed(gt: MotTable, seed: int) -> MotTable:
    """A plausible tracker output made from ground truth, with every kind of error.

    Boxes jittered by 8 % of their size, 15 % dropped, IDs swapped between tracks and
    tracks split under a new ID (switches, fragments), near-duplicates and clutter added
    (competing pairs), rows shuffled within frames.
    """
    rng = np.random.default_rng(seed)
    keep = rng.random(len(gt)) > 0.15
    t = gt.take(np.flatnonzero(keep))
    wh = t.tlwh[:, 2:]
    tlwh = t.tlwh + rng.normal(0.0, 0.08, (len(t), 4)) * np.hstack([wh, wh])
    tlwh[:, 2:] = np.abs(tlwh[:, 2:]) + 1.0
    ids = t.id.copy() * 10
    ids_u = np.unique(ids)
    for _ in range(max(1, ids_u.size // 3)):  # swaps from a random frame on
        a, b = rng.choice(ids_u, 2, replace=False)
        f0 = rng.integers(t.frame.min(), t.frame.max() + 1)
        late = t.frame >= f0
        ia, ib = late & (ids == a), late & (ids == b)
        ids[ia], ids[ib] = b, a
    split = rng.random(len(t)) < 0.02  # a new ID from a random row on, for some tracks
    for row in np.flatnonzero(split):
        ids[(ids == ids[row]) & (t.frame >= t.frame[row])] = ids.max() + 1
    dup = np.flatnonzero(rng.random(len(t)) < 0.1)
    dup_box = tlwh[dup] + rng.normal(0.0, 0.1, (dup.size, 4)) * np.hstack([wh[dup], wh[dup]])
    dup_box[:, 2:] = np.abs(dup_box[:, 2:]) + 1.0
    clutter = np.flatnonzero(rng.random(len(t)) < 0.1)
    clut_box = tlwh[clutter] + np.hstack([rng.uniform(-2, 2, (clutter.size, 2)) * wh[clutter],
                                          np.zeros((clutter.size, 2))])
    frame = np.concatenate([t.frame, t.frame[dup], t.frame[clutter]])
    n_extra = dup.size + clutter.size
    ids = np.concatenate([ids, ids.max() + 1 + np.arange(n_extra)])
    boxes = np.vstack([tlwh, dup_box, clut_box])
    order = np.lexsort((rng.random(frame.size), frame))
    k = frame.size
    return MotTable(frame[order], ids[order], boxes[order], np.ones(k), np.full(k, -1),
                    np.full(k, -1.0))


def _real(shared: Path, seq: str) -> Path:
    return shared / "data" / "real" / seq / "gt.txt"


# --------------------------------------------------------------------------- motmetrics


@pytest.mark.parametrize("seq", SEQS)
def test_tud_matches_values_asserted_by_motmetrics_tests(seq: str) -> None:
    ours = evaluate(TUD / seq / "gt.txt", TUD / seq / "test.txt", iou=0.5)
    expected = MOTMETRICS_EXPECTED[seq]
    got = [ours[k] for k in OUR_KEYS] + [1.0 - ours["MOTP"]]
    np.testing.assert_allclose(got, expected, atol=1e-6)


@pytest.mark.parametrize("iou", [0.3, 0.5, 0.7])
@pytest.mark.parametrize("seq", SEQS)
def test_tud_equals_motmetrics_accumulator_exactly(seq: str, iou: float) -> None:
    gt, pred = read_tracks(TUD / seq / "gt.txt", "gt"), read_tracks(TUD / seq / "test.txt")
    ref = _motmetrics_direct(gt, pred, iou)
    result = score_sequence(gt, pred, iou, with_hota=False)
    ours = result.as_dict()
    assert {k: ours[v] for k, v in EXACT.items()} == {k: ref[k] for k in EXACT}
    c = result.clear
    assert c.distance_sum / c.num_detections == ref["motp"]  # to the last bit
    assert c.num_frames == ref["num_frames"]


@pytest.mark.shared
@pytest.mark.parametrize("seq", REAL)
def test_perturbed_results_equal_motmetrics_with_every_row_counted(
    shared_dir: Path, seq: str
) -> None:
    """``ignore="none"``: all rows scored; swaps, splits, duplicates and clutter."""
    gt = read_tracks(_real(shared_dir, seq), "gt")
    for seed in range(2):
        pred = perturbed(gt, seed)
        ref = _motmetrics_direct(gt, pred)
        result = score_sequence(gt, pred, ignore="none", with_hota=False)
        ours = result.as_dict()
        assert {k: ours[v] for k, v in EXACT.items()} == {k: ref[k] for k in EXACT}, seed
        assert result.clear.distance_sum / result.clear.num_detections == ref["motp"]


@pytest.mark.shared
@pytest.mark.parametrize("seq", REAL)
def test_drop_equals_peerbench_scoring_to_the_last_digit(
    shared_dir: Path, tmp_path: Path, seq: str
) -> None:
    """``ignore="drop"`` on files: the figures of peerbench's metrics.py, bit for bit."""
    gt_path = _real(shared_dir, seq)
    gt = read_tracks(gt_path, "gt")
    res = write_results(tmp_path / f"{seq}.txt", perturbed(gt, 5), decimals=2)
    ref = _peerbench(shared_dir, gt_path, res)
    result = score_sequence(gt_path, res, ignore="drop", with_hota=False)
    ours = result.as_dict()
    pairs = {"num_frames": "num_frames", **{k: v for k, v in EXACT.items() if k in ref}}
    assert {k: ours[v] for k, v in pairs.items()} == {k: ref[k] for k in pairs}
    assert result.clear.distance_sum / result.clear.num_detections == ref["motp"]
    assert ref["num_misses"] > 0 and ref["num_switches"] > 0  # the case is not trivial


# --------------------------------------------------------------------------- TrackEval


def test_hota_matches_trackeval_own_mot_pipeline_on_tud(tmp_path: Path) -> None:
    """Our HOTA against TrackEval's MOTChallenge loader (MOT15 mode: no preprocessing)."""
    gts = {seq: TUD / seq / "gt.txt" for seq in SEQS}
    ref = _trackeval(tmp_path, gts, {seq: TUD / seq / "test.txt" for seq in SEQS}, "MOT15")
    for seq in SEQS:
        ours = evaluate(gts[seq], TUD / seq / "test.txt")
        for key in ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr"):
            assert ours[key] == pytest.approx(float(np.mean(ref[seq]["HOTA"][key])), abs=1e-12)
        assert ours["IDF1"] == pytest.approx(ref[seq]["Identity"]["IDF1"], abs=1e-12)


@pytest.mark.shared
@pytest.mark.parametrize(("benchmark", "ignore"), [("MOT15", "drop"), ("MOT17", "distractor")])
def test_real_sequences_match_trackeval(
    shared_dir: Path, tmp_path: Path, benchmark: str, ignore: str
) -> None:
    """HOTA and IDF1 per sequence and combined; ``distractor`` as TrackEval's MOT17 rule."""
    from mvtrack.eval.sequences import Sequence, evaluate_sequences

    gts = {seq: _real(shared_dir, seq) for seq in REAL}
    results = {
        seq: write_results(tmp_path / "res" / f"{seq}.txt",
                           perturbed(read_tracks(gts[seq], "gt"), 7), decimals=2)
        for seq in REAL
    }
    ref = _trackeval(tmp_path / "te", gts, results, benchmark)
    per, combined = evaluate_sequences(
        [Sequence(s, gts[s], results[s]) for s in REAL], ignore=ignore  # type: ignore[arg-type]
    )
    for seq, scores in [*((s, per[s].as_dict()) for s in REAL),
                        ("COMBINED_SEQ", combined.as_dict())]:
        r = ref[seq]
        for key in ("HOTA", "DetA", "AssA", "LocA"):
            assert scores[key] == pytest.approx(float(np.mean(r["HOTA"][key])), abs=1e-12)
        assert scores["IDF1"] == pytest.approx(r["Identity"]["IDF1"], abs=1e-12)
        # The predictions TrackEval kept after its preprocessing: matched plus FP.
        assert scores["num_pred_dets"] == r["CLEAR"]["CLR_TP"] + r["CLEAR"]["CLR_FP"]
    removed = sum(per[s].num_ignored_pred for s in REAL)
    assert removed > 0 if ignore == "distractor" else removed == 0


def _trackeval_hota_class() -> Any:
    """TrackEval's HOTA metric class: the package's, or its released files in tests/reference."""
    sink = io.StringIO()
    for name in ("trackeval.metrics", "reference.trackeval.metrics"):
        try:
            with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
                module = importlib.import_module(name)
        except ImportError:
            continue
        return module.HOTA
    pytest.skip("TrackEval's HOTA class is not available")


def _trackeval_hota_dense(gt: MotTable, pred: MotTable) -> dict[str, float]:
    """TrackEval's own ``HOTA.eval_sequence`` on the dense per-frame data it expects."""
    n = max(gt.num_frames, pred.num_frames)
    gid = np.unique(gt.id, return_inverse=True)[1].reshape(-1)
    pid = np.unique(pred.id, return_inverse=True)[1].reshape(-1)
    g_rows = [np.flatnonzero(gt.frame == f) for f in range(n)]
    p_rows = [np.flatnonzero(pred.frame == f) for f in range(n)]
    data = {
        "num_timesteps": n, "num_gt_ids": int(gid.max()) + 1 if gid.size else 0,
        "num_tracker_ids": int(pid.max()) + 1 if pid.size else 0,
        "num_gt_dets": len(gt), "num_tracker_dets": len(pred),
        "gt_ids": [gid[r] for r in g_rows], "tracker_ids": [pid[r] for r in p_rows],
        "similarity_scores": [iou_matrix(gt.tlwh[g], pred.tlwh[p])
                              for g, p in zip(g_rows, p_rows, strict=True)],
    }
    res = _trackeval_hota_class()().eval_sequence(data)
    keys = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr")
    return {k: float(np.mean(res[k])) for k in keys}


@pytest.mark.parametrize("seed", [0, 1])
def test_hota_equals_trackeval_metric_class_on_dense_frames(seed: int) -> None:
    """The sparse HOTA against TrackEval's metric class fed every frame's dense IoU matrix
    (TUD-Campus ground truth, perturbed: switches, duplicates, clutter)."""
    gt = read_tracks(TUD / "TUD-Campus" / "gt.txt", "gt")
    pred = perturbed(gt, seed)
    ref = _trackeval_hota_dense(gt, pred)
    ours = evaluate(gt, pred)
    for key, value in ref.items():
        assert ours[key] == pytest.approx(value, abs=1e-12), key


# --------------------------------------------------------------------------- hand-computed


def _track(frames: list[int], ids: list[int], tlwh: Any, flag: Any = 1.0) -> MotTable:
    k = len(frames)
    tlwh = np.broadcast_to(np.asarray(tlwh, float), (k, 4))
    return MotTable(frames, ids, tlwh, np.broadcast_to(np.asarray(flag, float), (k,)),
                    np.full(k, -1), np.full(k, -1.0))


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
    assert s["IDF1"] == pytest.approx(0.5) and s["IDTP"] == 2
    # HOTA: every box matched at every α (DetA = 1); each of the two (gt, pred) ID pairs has
    # TPA = 2, FNA = 2, FPA = 0 → A = 2/4, so AssA = 0.5, AssRe = 0.5, AssPr = 1, HOTA = √0.5.
    assert s["DetA"] == pytest.approx(1.0)
    assert s["AssA"] == pytest.approx(0.5)
    assert s["AssRe"] == pytest.approx(0.5) and s["AssPr"] == pytest.approx(1.0)
    assert s["HOTA"] == pytest.approx(np.sqrt(0.5))


def test_kept_match_wins_over_a_closer_newcomer_and_gap_counts_a_fragment() -> None:
    # Frame 0: only prediction 5 on the person. Frame 1: prediction 6 sits exactly on the
    # person, 5 is still valid (IoU 0.68): 5 keeps it (no switch), 6 is a false positive.
    # Frame 2: no prediction (a miss); frame 3: 5 again — one fragmentation.
    gt = _track([0, 1, 2, 3], [1, 1, 1, 1], [0, 0, 10, 10])
    pred = MotTable([0, 1, 1, 3], [5, 5, 6, 5],
                    [[0, 0, 10, 10], [0, 0, 10, 6.8], [0, 0, 10, 10], [0, 0, 10, 10]],
                    np.ones(4), np.full(4, -1), np.full(4, -1.0))
    s = evaluate(gt, pred, with_hota=False)
    assert (s["IDSW"], s["FP"], s["FN"], s["FM"], s["num_matches"]) == (0, 1, 1, 1, 3)
    assert s["MOTP"] == pytest.approx((1 + 0.68 + 1) / 3)


def test_partial_overlap_counts_only_thresholds_below_its_iou() -> None:
    # Prediction overlaps the GT box with IoU 0.63 (same left/top/width, height 6.3 of 10).
    gt = _track([0, 1, 2], [1, 1, 1], [0, 0, 10, 10])
    pred = _track([0, 1, 2], [4, 4, 4], [0, 0, 10, 6.3])
    assert iou_matrix(gt.tlwh[:1], pred.tlwh[:1])[0, 0] == pytest.approx(0.63)
    # TrackEval's α grid is 0.05, 0.10, ..., 0.95: the 12 values up to 0.60 match.
    assert evaluate(gt, pred)["HOTA"] == pytest.approx(12 / 19)
    loose, strict = evaluate(gt, pred, iou=0.5), evaluate(gt, pred, iou=0.7)
    assert loose["MOTA"] == pytest.approx(1.0) and loose["MOTP"] == pytest.approx(0.63)
    assert (strict["FP"], strict["FN"]) == (3, 3) and strict["MOTA"] == pytest.approx(-1.0)


@pytest.mark.parametrize(
    ("ignore", "expected"),
    [("drop", (0.0, 1, 1, 1, 0)), ("distractor", (1.0, 0, 1, 1, 1)), ("none", (1.0, 0, 2, 0, 0))],
)
def test_ignore_flag_modes_on_a_hand_made_frame(
    ignore: str, expected: tuple[float, int, int, int, int]
) -> None:
    # Two people, one of them 0-marked; the tracker covers both. drop: the box on the
    # 0-marked person is a false positive; distractor: it is removed; none: it is a hit.
    gt = MotTable([0, 0], [1, 2], [[0, 0, 10, 20], [50, 0, 10, 20]], [1.0, 0.0], [-1, -1],
                  [-1.0, -1.0])
    pred = _track([0, 0], [7, 8], [[0, 0, 10, 20], [51, 0, 10, 20]])
    s = evaluate(gt, pred, ignore=ignore, check=False)  # type: ignore[arg-type]
    mota, fp, gt_boxes, ignored_gt, ignored_pred = expected
    got = (s["MOTA"], s["FP"], s["num_gt_dets"], s["num_ignored_gt"], s["num_ignored_pred"])
    assert got == (pytest.approx(mota), fp, gt_boxes, ignored_gt, ignored_pred)


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


def test_bad_iou_threshold_and_ignore_mode_are_rejected() -> None:
    gt = _track([0], [1], [0, 0, 10, 10])
    with pytest.raises(ValueError, match="iou"):
        evaluate(gt, gt, iou=0.0)
    with pytest.raises(ValueError, match="ignore"):
        evaluate(gt, gt, ignore="keep")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- scale


def test_memory_grows_with_rows_not_with_frame_numbers() -> None:
    """Two boxes a billion frames apart: a per-frame structure up to the last frame would
    need gigabytes."""
    gt = _track([0, 10**9], [1, 1], [0, 0, 10, 10])
    pred = _track([0, 10**9], [3, 4], [0, 0, 10, 10])
    tracemalloc.start()
    try:
        s = evaluate(gt, pred)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert (s["IDSW"], s["num_frames"], s["HOTA"] > 0.5) == (1, 10**9 + 1, True)
    assert peak < 20e6, peak


def test_crowded_frames_match_dense_evaluation(tmp_path: Path) -> None:
    """200 targets in one image: the sparse pair search and assignment give the figures of
    motmetrics' dense per-frame matrices."""
    rng = np.random.default_rng(11)
    n, frames = 200, 4
    xy = rng.uniform(0, 1000, (n, 2))
    v = rng.normal(0, 4, (n, 2))
    f = np.repeat(np.arange(frames), n)
    ids = np.tile(np.arange(1, n + 1), frames)
    pos = xy[None] + v[None] * np.arange(frames)[:, None, None]
    wh = np.broadcast_to(rng.uniform(20, 60, (n, 2)), (frames, n, 2))
    gt = MotTable(f, ids, np.concatenate([pos, wh], axis=2).reshape(-1, 4), np.ones(f.size),
                  np.full(f.size, -1), np.full(f.size, -1.0))
    pred = perturbed(gt, 1)
    ref = _motmetrics_direct(gt, pred)
    ours = evaluate(gt, pred, with_hota=False)
    assert {k: ours[v] for k, v in EXACT.items()} == {k: ref[k] for k in EXACT}
    write_mot(tmp_path / "gt.txt", gt, "gt")  # the same through files
    write_results(tmp_path / "res.txt", pred, decimals=6)
    again = evaluate(tmp_path / "gt.txt", tmp_path / "res.txt", with_hota=False)
    assert again["MOTA"] == pytest.approx(ours["MOTA"], abs=1e-3)


box = st.tuples(
    st.integers(0, 3), st.floats(-20, 200), st.floats(-20, 200), st.floats(0, 80),
    st.floats(0, 80),
)


@settings(max_examples=60, deadline=None)
@given(st.lists(box, max_size=25), st.lists(box, max_size=25))
def test_overlapping_pairs_are_exactly_the_positive_cells_of_the_dense_matrices(
    a: list[tuple[int, float, float, float, float]],
    b: list[tuple[int, float, float, float, float]],
) -> None:
    fa = np.array([r[0] for r in a], dtype=np.int64)
    fb = np.array([r[0] for r in b], dtype=np.int64)
    ta, tb = np.array([r[1:] for r in a]).reshape(-1, 4), np.array([r[1:] for r in b]).reshape(
        -1, 4)
    pairs = overlapping_pairs(fa, ta, fb, tb)
    expect = []
    for f in np.unique(fa):
        rows_a, rows_b = np.flatnonzero(fa == f), np.flatnonzero(fb == f)
        m = iou_matrix(ta[rows_a], tb[rows_b])
        i, j = np.nonzero(m > 0)
        expect += list(zip(rows_a[i].tolist(), rows_b[j].tolist(), m[i, j].tolist(), strict=True))
    got = zip(pairs.a.tolist(), pairs.b.tolist(), pairs.iou.tolist(), strict=True)
    assert list(got) == expect


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_shuffling_rows_within_frames_changes_no_score(seed: int) -> None:
    rng = np.random.default_rng(seed)
    gt = _track(list(np.repeat(np.arange(8), 5)), list(np.tile(np.arange(5), 8)),
                np.column_stack([rng.uniform(0, 100, (40, 2)), rng.uniform(10, 30, (40, 2))]))
    pred = perturbed(gt, seed)
    shuffle = np.lexsort((rng.random(len(pred)), pred.frame))
    a, b = evaluate(gt, pred), evaluate(gt, pred.take(shuffle))
    for key in ("MOTA", "IDF1", "HOTA", "AssA", "IDSW", "FP", "FN", "FM"):
        assert a[key] == pytest.approx(b[key], abs=1e-12), key
