"""An --out folder holds one run: a rerun replaces the earlier run's files as a whole, a folder
with other files is refused without --force, a failed run leaves the earlier one as it was,
and a bad --out is one line naming the option."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from _media import box_video
from mvtrack.cli import main
from mvtrack.errors import InputError
from mvtrack.io.outdir import foreign_entries, run_folder


def _err(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("error: "), err
    assert "Traceback" not in err and "Errno" not in err
    return err


def _names(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir()}


def test_a_rerun_replaces_the_earlier_runs_files(tmp_path: Path, capsys) -> None:
    video = box_video(tmp_path / "v.avi", n=30)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--snapshot", "20"]) == 0
    (out / "report.html").write_text("<html>an earlier report</html>")  # mvtrack report's
    assert {"tracks.mp4", "frame00020.png", "report.html"} <= _names(out)
    capsys.readouterr()
    assert main(["track", str(video), "--out", str(out), "--no-video",
                 "--max-frames", "12"]) == 0
    assert _names(out) == {"results.txt", "states.csv", "summary.json", "trajectories.png"}
    assert json.loads((out / "summary.json").read_text())["frames"] == 12


def test_a_folder_with_other_files_is_refused_and_force_keeps_them(tmp_path: Path,
                                                                    capsys) -> None:
    video = box_video(tmp_path / "v.avi", n=20)
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("my notes")
    assert main(["track", str(video), "--out", str(out), "--no-video"]) == 2
    err = _err(capsys)
    assert f"--out {out} is not empty and is not the folder of an earlier mvtrack run" in err
    assert "'notes.txt'" in err and "--force" in err
    assert _names(out) == {"notes.txt"}
    assert main(["track", str(video), "--out", str(out), "--no-video", "--force"]) == 0
    assert (out / "notes.txt").read_text() == "my notes"
    assert {"results.txt", "summary.json", "notes.txt"} <= _names(out)
    # the folder now mixes a run and other files: a rerun still needs --force
    capsys.readouterr()
    assert main(["track", str(video), "--out", str(out), "--no-video"]) == 2
    assert "'notes.txt'" in _err(capsys)


def test_a_failed_run_leaves_the_earlier_run_as_it_was(tmp_path: Path, capsys) -> None:
    video = box_video(tmp_path / "v.avi", n=20)
    out = tmp_path / "out"
    assert main(["track", str(video), "--out", str(out), "--no-video"]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    bad = tmp_path / "bad.avi"
    bad.write_bytes(b"not a video" * 20)
    assert main(["track", str(bad), "--out", str(out)]) == 2
    assert "bad.avi" in _err(capsys)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_the_folder_of_the_input_is_never_replaced(tmp_path: Path, capsys) -> None:
    out = tmp_path / "scene"
    assert main(["simulate", "x5", "--frames", "20", "--out", str(out)]) == 0
    capsys.readouterr()
    video = out / "video.mp4"
    assert main(["track", str(video), "--out", str(out), "--no-video"]) == 2
    err = _err(capsys)
    assert f"--out {out} holds the input {video}" in err
    assert _names(out) == {"gt.txt", "video.mp4", "scene.json"}


def test_simulate_rerun_drops_the_files_the_new_run_does_not_make(tmp_path: Path,
                                                                    capsys) -> None:
    out = tmp_path / "crowd"
    assert main(["simulate", "crowd", "--n", "5", "--frames", "10", "--detections",
                 "--out", str(out)]) == 0
    assert "det.txt" in _names(out)
    assert main(["simulate", "crowd", "--n", "5", "--frames", "10", "--out", str(out)]) == 0
    assert _names(out) == {"gt.txt", "scene.json"}  # no stale det.txt


def test_demo_reruns_into_its_own_folder(tmp_path: Path, capsys) -> None:
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--frames", "20", "--no-video"]) == 0
    (out / "tracks.mp4").write_bytes(b"an earlier video")
    assert main(["demo", "--out", str(out), "--frames", "20", "--no-video"]) == 0
    assert "tracks.mp4" not in _names(out) and "metrics.json" in _names(out)


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda t: (t / "afile").write_text("x") and t / "afile", "is a file, not a folder"),
        (lambda t: (t / "afile").write_text("x") and t / "afile" / "sub",
         "afile is a file, not a folder"),
        (lambda t: Path("/proc/mvtrack-test"), "cannot create a folder in /proc"),
    ],
)
@pytest.mark.parametrize("command", ["track", "demo", "simulate", "track-detections", "batch"])
def test_a_bad_out_is_one_line_naming_the_option(tmp_path: Path, capsys, make, fragment,
                                                 command: str) -> None:
    if not Path("/proc").is_dir() and "proc" in fragment:
        pytest.skip("no /proc here")
    out = make(tmp_path)
    video = box_video(tmp_path / "v.avi", n=10)
    det = tmp_path / "det.txt"
    det.write_text("1,-1,10,10,20,40,0.9\n")
    args = {
        "track": ["track", str(video)], "demo": ["demo", "--frames", "5"],
        "simulate": ["simulate", "x7"], "track-detections": ["track-detections", str(det)],
        "batch": ["batch", str(video), "--workers", "1"],
    }[command]
    assert main([*args, "--out", str(out)]) == 2
    err = _err(capsys)
    assert f"--out {out}" in err and fragment in err


def test_run_folder_restores_the_earlier_run_on_any_exception(tmp_path: Path) -> None:
    out = tmp_path / "run"
    out.mkdir()
    (out / "results.txt").write_text("old\n")
    (out / "summary.json").write_text(json.dumps({"source": "a", "frames": 1, "video_fps": 30,
                                                  "files": {}}))
    assert foreign_entries(out) == []
    with pytest.raises(KeyboardInterrupt), run_folder(out) as folder:
        assert _names(folder) and all(p.name.startswith(".") for p in folder.iterdir())
        (folder / "results.txt").write_text("half\n")
        raise KeyboardInterrupt
    assert (out / "results.txt").read_text() == "old\n" and len(_names(out)) == 2
    with run_folder(out) as folder:
        (folder / "results.txt").write_text("new\n")
    assert _names(out) == {"results.txt"}


def test_run_folder_of_the_working_directory(tmp_path: Path, monkeypatch) -> None:
    """An earlier run in the shell's own folder (--out .) is replaced in place: the folder
    itself is never moved, so the shell and relative paths stay where they were."""
    monkeypatch.chdir(tmp_path)
    Path("results.txt").write_text("old\n")
    Path("summary.json").write_text(json.dumps({"source": "a", "frames": 1, "video_fps": 30,
                                                "files": {}}))
    with run_folder(Path(".")):
        Path("results.txt").write_text("new\n")
        assert os.getcwd() == str(tmp_path)
    assert _names(tmp_path) == {"results.txt"}


def test_a_folder_that_only_looks_like_a_run_is_foreign(tmp_path: Path) -> None:
    (tmp_path / "summary.json").write_text('{"my": "own summary"}')
    (tmp_path / "results.txt").write_text("x\n")
    assert foreign_entries(tmp_path) == ["results.txt", "summary.json"]
    with pytest.raises(InputError, match="not the folder of an earlier mvtrack run"), \
            run_folder(tmp_path):
        pass


def test_the_readme_examples_run_twice(tmp_path: Path, monkeypatch, capsys) -> None:
    """Rerunning the README's commands: the simulated scene's folder holds the runs made from
    it (a track run, a folder of track-detections results) and is replaced with them."""
    monkeypatch.chdir(tmp_path)
    for _ in range(2):
        assert main(["simulate", "x5", "--frames", "20", "--out", "out/x5"]) == 0
        assert main(["track", "out/x5/video.mp4", "--out", "out/x5/track", "--snapshot", "10",
                     "--no-video"]) == 0
        assert main(["simulate", "crowd", "--n", "10", "--frames", "20", "--detections",
                     "--out", "out/crowd"]) == 0
        assert main(["track-detections", "out/crowd/det.txt", "--out", "out/crowd/res",
                     "--fps", "30"]) == 0
    assert _names(Path("out/x5")) == {"gt.txt", "video.mp4", "scene.json", "track"}
    assert _names(Path("out/crowd/res")) == {"det.txt"}
    # a file of the user's own beside them is never deleted
    Path("out/crowd/res/notes.txt").write_text("mine")
    assert main(["simulate", "crowd", "--n", "10", "--frames", "20", "--out", "out/crowd"]) == 2
    assert "'res/'" in _err(capsys)
    assert Path("out/crowd/res/notes.txt").read_text() == "mine"


def test_another_commands_folder_is_not_replaced(tmp_path: Path, capsys) -> None:
    """A simulated scene's folder (its ground truth and detections) is not a track run's:
    tracking into it is refused, and --force writes beside its files."""
    scene = tmp_path / "crowd"
    assert main(["simulate", "crowd", "--n", "5", "--frames", "10", "--detections",
                 "--out", str(scene)]) == 0
    video = box_video(tmp_path / "v.avi", n=10)
    capsys.readouterr()
    assert main(["track", str(video), "--out", str(scene), "--no-video"]) == 2
    assert f"--out {scene} holds a run of mvtrack simulate, not of mvtrack track" in _err(capsys)
    assert _names(scene) == {"gt.txt", "det.txt", "scene.json"}
    assert main(["track", str(video), "--out", str(scene), "--no-video", "--force"]) == 0
    assert {"gt.txt", "det.txt", "scene.json", "results.txt"} <= _names(scene)
