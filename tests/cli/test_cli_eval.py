"""``mvtrack eval``: table and JSON on motmetrics' TUD example, a folder of sequences, the
ignore flag; inputs that cannot belong together refused with one line, suspicious ones warned
about; no partial JSON."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import motmetrics as mm
import pytest

from mvtrack.cli import main

CAMPUS = Path(mm.__file__).parent / "data" / "TUD-Campus"
STADTMITTE = Path(mm.__file__).parent / "data" / "TUD-Stadtmitte"


def test_eval_prints_table_and_writes_json(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "sub" / "scores.json"
    status = main([
        "eval", "--gt", str(CAMPUS / "gt.txt"), "--pred", str(CAMPUS / "test.txt"),
        "--json", str(out),
    ])
    assert status == 0
    printed = capsys.readouterr().out
    assert any(line.split() == ["MOTA", "0.526"] for line in printed.splitlines()), printed
    assert any(line.split() == ["ID", "switches", "7"] for line in printed.splitlines())
    scores = json.loads(out.read_text())
    # motmetrics' own tests assert MOTA 0.526462 and IDF1 0.557659 for this pair of files.
    assert scores["MOTA"] == pytest.approx(0.526462, abs=1e-6)
    assert scores["IDF1"] == pytest.approx(0.557659, abs=1e-6)
    assert scores["iou_threshold"] == 0.5 and scores["gt"].endswith("gt.txt")
    assert 0.0 < scores["HOTA"] < 1.0


def test_stricter_iou_lowers_mota(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "s.json"
    args = ["eval", "--gt", str(CAMPUS / "gt.txt"), "--pred", str(CAMPUS / "test.txt")]
    assert main([*args, "--iou", "0.8", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["MOTA"] < 0.526


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (None, "no such file"),
        ("1,1,10,10,5,5,1,-1,-1,-1\n1,2,10,10,5\n", "res.txt:2: expected 6 to 10 columns"),
        ("1,1,10,10,5,5,1,-1,-1,-1\n2,1,10,10,-5,5,1,-1,-1,-1\n", "res.txt:2: negative width"),
    ],
)
def test_bad_prediction_file_is_one_line_error_and_no_json(
    tmp_path: Path, capsys: pytest.CaptureFixture, content: str | None, fragment: str
) -> None:
    pred = tmp_path / "res.txt"
    if content is not None:
        pred.write_text(content)
    out = tmp_path / "scores.json"
    status = main(["eval", "--gt", str(CAMPUS / "gt.txt"), "--pred", str(pred), "--json", str(out)])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert err.count("\n") == 0 and err.startswith("error:") and fragment in err, err
    assert not out.exists() and sorted(tmp_path.iterdir()) == sorted(
        [pred] if content is not None else []
    )


def test_eval_output_has_no_import_noise(tmp_path: Path) -> None:
    """TrackEval prints about pycocotools on import; the command must not pass that on."""
    proc = subprocess.run(
        [sys.executable, "-m", "mvtrack", "eval", "--gt", str(CAMPUS / "gt.txt"),
         "--pred", str(CAMPUS / "test.txt")],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert "pycocotools" not in proc.stdout + proc.stderr
    assert proc.stdout.splitlines()[0].split() == ["MOTA", "0.526"]


def test_empty_prediction_gives_zero_mota_and_strict_json(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    pred = tmp_path / "empty.txt"
    pred.write_text("")
    out = tmp_path / "s.json"
    args = ["eval", "--gt", str(CAMPUS / "gt.txt"), "--pred", str(pred), "--json", str(out)]
    assert main(args) == 0
    text = out.read_text()
    assert "NaN" not in text and "Infinity" not in text
    scores = json.loads(text)
    assert scores["MOTA"] == 0.0 and scores["FN"] == 359 and scores["MOTP"] is None


def _run(capsys: pytest.CaptureFixture, *args: str) -> tuple[int, str, str]:
    status = main(["eval", *args])
    cap = capsys.readouterr()
    return status, cap.out, cap.err


def _write(path: Path, rows: list[str]) -> Path:
    path.write_text("".join(r + "\n" for r in rows))
    return path


GT_ROWS = ["1,1,10,10,20,40,1,-1,-1", "2,1,12,10,20,40,1,-1,-1", "2,2,200,50,20,40,0,-1,-1"]


@pytest.mark.parametrize(
    ("gt_rows", "pred_rows", "fragment"),
    [
        ([], ["1,1,10,10,20,40,1,-1,-1,-1"], "ground truth has no rows"),
        (["1,1,10,10,20,40,0,-1,-1"], ["1,1,10,10,20,40,1,-1,-1,-1"], "ignore flag"),
        (GT_ROWS, ["5,1,10,10,20,40,1,-1,-1,-1", "9,1,10,10,20,40,1,-1,-1,-1"],
         "share no frame with the ground truth (ground truth frames 1–2, results frames 5–9)"),
        (GT_ROWS, ["1,1,900,600,20,40,1,-1,-1,-1"], "no result box intersects the extent"),
        # IDs that float64 cannot hold exactly, or int64 not at all (the message names the id).
        (GT_ROWS, ["1,100000000000000000000,10,10,20,40,1,-1,-1,-1"], "id"),
        (GT_ROWS, ["1,9007199254740993,10,10,20,40,1,-1,-1,-1"], "id"),
    ],
)
def test_inputs_that_cannot_belong_together_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, gt_rows: list[str], pred_rows: list[str],
    fragment: str,
) -> None:
    gt = _write(tmp_path / "gt.txt", gt_rows)
    pred = _write(tmp_path / "res.txt", pred_rows)
    out = tmp_path / "s.json"
    status, _, err = _run(capsys, "--gt", str(gt), "--pred", str(pred), "--json", str(out))
    assert status == 2
    lines = err.strip().splitlines()
    # One error line naming the problem (no reader's warning about an empty file before it).
    assert len(lines) == 1 and lines[0].startswith("error:") and fragment in lines[0], err
    if fragment == "id":
        assert "res.txt" in lines[-1], err
    assert not out.exists()


def test_results_of_another_sequence_are_scored_with_warnings(
    capsys: pytest.CaptureFixture,
) -> None:
    """TUD-Stadtmitte's results against TUD-Campus's ground truth: same image size, frames
    overlapping: scored (MOTA far below 0), with two warnings saying why it looks wrong."""
    status, out, err = _run(capsys, "--gt", str(CAMPUS / "gt.txt"),
                            "--pred", str(STADTMITTE / "test.txt"))
    assert status == 0
    warnings = err.strip().splitlines()
    assert len(warnings) == 2 and all(w.startswith("warning: ") for w in warnings), err
    assert "after the last ground-truth frame (71)" in warnings[0]
    assert "results of another sequence?" in warnings[1]
    assert float(out.splitlines()[0].split()[1]) < -1.0
    status, _, err = _run(capsys, "--gt", str(CAMPUS / "gt.txt"),
                          "--pred", str(CAMPUS / "test.txt"))
    assert status == 0 and err == ""  # the right pair: no warning


def test_ignore_modes_on_a_zero_flag_person(tmp_path: Path, capsys: pytest.CaptureFixture
                                            ) -> None:
    gt = _write(tmp_path / "gt.txt", GT_ROWS)
    pred = _write(tmp_path / "res.txt", ["1,5,10,10,20,40,1,-1,-1,-1",
                                          "2,5,12,10,20,40,1,-1,-1,-1",
                                          "2,6,201,50,20,40,1,-1,-1,-1"])
    got = {}
    for mode in ("drop", "distractor", "none"):
        out = tmp_path / f"{mode}.json"
        args = ["--gt", str(gt), "--pred", str(pred), "--ignore", mode, "--json", str(out)]
        assert _run(capsys, *args)[0] == 0
        s = json.loads(out.read_text())
        got[mode] = (s["FP"], s["num_gt_dets"], s["num_ignored_pred"], s["ignore"])
    assert got == {"drop": (1, 2, 0, "drop"), "distractor": (0, 2, 1, "distractor"),
                   "none": (0, 3, 0, "none")}
    status, _, err = _run(capsys, "--gt", str(gt), "--pred", str(pred), "--ignore", "keep")
    assert status == 2 and "--ignore: unknown value 'keep'" in err


def _folders(tmp_path: Path) -> tuple[Path, Path]:
    """TUD-Campus in the MOTChallenge layout, TUD-Stadtmitte in the layout of data/real."""
    gt, res = tmp_path / "gt", tmp_path / "res"
    (gt / "TUD-Campus" / "gt").mkdir(parents=True)
    (gt / "TUD-Stadtmitte").mkdir(parents=True)
    (res / "TUD-Stadtmitte").mkdir(parents=True)
    shutil.copy(CAMPUS / "gt.txt", gt / "TUD-Campus" / "gt" / "gt.txt")
    shutil.copy(STADTMITTE / "gt.txt", gt / "TUD-Stadtmitte" / "gt.txt")
    shutil.copy(CAMPUS / "test.txt", res / "TUD-Campus.txt")
    shutil.copy(STADTMITTE / "test.txt", res / "TUD-Stadtmitte" / "det.txt")
    return gt, res


def test_folder_gives_one_row_per_sequence_and_a_combined_row_of_summed_counts(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    gt, res = _folders(tmp_path)
    out = tmp_path / "s.json"
    status, printed, err = _run(capsys, "--gt", str(gt), "--pred", str(res), "--json", str(out))
    assert status == 0 and err == ""
    rows = [line for line in printed.splitlines() if line.startswith("| ")]
    assert [r.split("|")[1].strip() for r in rows] == [
        "sequence", "TUD-Campus", "TUD-Stadtmitte", "COMBINED (summed counts)"]
    s = json.loads(out.read_text())
    campus, stadt, both = s["sequences"]["TUD-Campus"], s["sequences"]["TUD-Stadtmitte"], s[
        "combined"]
    # motmetrics' test values for the two files (MOTA 0.526462 and 0.564014).
    assert campus["MOTA"] == pytest.approx(0.526462, abs=1e-6)
    assert stadt["MOTA"] == pytest.approx(0.564014, abs=1e-6)
    for key in ("FP", "FN", "IDSW", "num_gt_dets", "IDTP", "MT", "FM"):
        assert both[key] == campus[key] + stadt[key], key
    errors = both["FP"] + both["FN"] + both["IDSW"]
    assert both["MOTA"] == pytest.approx(1 - errors / both["num_gt_dets"], abs=1e-15)
    assert both["MOTA"] != pytest.approx((campus["MOTA"] + stadt["MOTA"]) / 2, abs=1e-3)
    # motmetrics combines the two accumulators the same way (its OVERALL row).
    overall = _motmetrics_overall()
    assert both["MOTA"] == pytest.approx(overall["mota"], abs=1e-12)
    assert both["IDF1"] == pytest.approx(overall["idf1"], abs=1e-12)


def _motmetrics_overall() -> dict[str, float]:
    import numpy as np

    accs = []
    for folder in (CAMPUS, STADTMITTE):
        gt = mm.io.loadtxt(str(folder / "gt.txt"))
        dt = mm.io.loadtxt(str(folder / "test.txt"))
        acc = mm.MOTAccumulator()
        fields = ["X", "Y", "Width", "Height"]
        g_by, d_by = dict(iter(gt[fields].groupby("FrameId"))), dict(iter(dt[fields].groupby(
            "FrameId")))
        for fid in sorted(set(g_by) | set(d_by)):
            g = g_by.get(fid, gt[fields].iloc[:0])
            d = d_by.get(fid, dt[fields].iloc[:0])
            dist = 1.0 - mm.distances.boxiou(g.to_numpy(float)[:, None], d.to_numpy(float)[None])
            dist = np.where(dist > 0.5, np.nan, dist).reshape(len(g), len(d))
            acc.update(g.index.get_level_values("Id"), d.index.get_level_values("Id"), dist,
                       frameid=fid)
        accs.append(acc)
    summary = mm.metrics.create().compute_many(
        accs, metrics=["mota", "idf1"], names=["a", "b"], generate_overall=True)
    return summary.loc["OVERALL"].to_dict()


def test_folder_with_a_sequence_missing_its_results_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    gt, res = _folders(tmp_path)
    (res / "TUD-Campus.txt").unlink()
    status, _, err = _run(capsys, "--gt", str(gt), "--pred", str(res))
    assert status == 2 and err.count("\n") == 1
    assert "no results for 1 of 2 sequences (TUD-Campus)" in err
    status, _, err = _run(capsys, "--gt", str(gt), "--pred", str(CAMPUS / "test.txt"))
    assert status == 2 and "both be files or both be folders" in err
