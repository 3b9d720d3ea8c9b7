"""``mvtrack eval``: table and JSON on motmetrics' TUD example; one-line errors, no partial JSON."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from mvtrack.cli import main

mm = pytest.importorskip("motmetrics")
CAMPUS = Path(mm.__file__).parent / "data" / "TUD-Campus"


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
