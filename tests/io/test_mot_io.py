"""MOTChallenge files: round trips, frame indexing, and one-line errors naming file and line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtrack.errors import InputError, InputWarning
from mvtrack.io.mot import (
    MotTable,
    read_detections,
    read_mot,
    read_tracks,
    write_detections,
    write_mot,
    write_results,
)
from mvtrack.types import Detections


def _random_table(rng: np.random.Generator, k: int = 40) -> MotTable:
    frame = rng.integers(0, 12, k)
    ids = np.arange(k) + 1  # unique, so no (frame, id) duplicates
    tlwh = np.column_stack([rng.uniform(-20, 600, (k, 2)), rng.uniform(0, 80, (k, 2))])
    return MotTable(frame, ids, tlwh, rng.uniform(0, 1, k), np.full(k, 1), rng.uniform(0, 1, k))


def test_results_round_trip_keeps_every_row(tmp_path: Path) -> None:
    table = _random_table(np.random.default_rng(0))
    path = write_results(tmp_path / "res.txt", table)
    back = read_tracks(path)
    order = np.lexsort((table.id, table.frame))
    np.testing.assert_array_equal(back.frame, table.frame[order])
    np.testing.assert_array_equal(back.id, table.id[order])
    np.testing.assert_allclose(back.tlwh, table.tlwh[order], atol=5e-4)
    np.testing.assert_allclose(back.conf, table.conf[order], rtol=1e-5)
    # Results files carry -1 in the last three columns.
    assert np.all(back.cls == -1) and np.all(back.visibility == -1)


def test_gt_round_trip_keeps_class_and_visibility(tmp_path: Path) -> None:
    table = _random_table(np.random.default_rng(1))
    back = read_tracks(write_mot(tmp_path / "gt.txt", table, kind="gt"), kind="gt")
    order = np.lexsort((table.id, table.frame))
    np.testing.assert_array_equal(back.cls, table.cls[order])
    np.testing.assert_allclose(back.visibility, table.visibility[order], rtol=1e-5)


def test_file_frames_are_one_based_and_internal_frames_zero_based(tmp_path: Path) -> None:
    path = tmp_path / "res.txt"
    path.write_text("3,7,10,20,30,40,0.9,-1,-1,-1\n")
    table = read_tracks(path)
    assert table.frame.tolist() == [2] and table.id.tolist() == [7]
    write_results(path, table)
    assert path.read_text().startswith("3,7,10.000,20.000,30.000,40.000,0.9,")


def test_detections_round_trip_with_empty_frames(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    frames = []
    for f in range(6):
        m = 0 if f in (0, 3) else int(rng.integers(1, 5))
        frames.append(
            Detections.from_tlwh(f, rng.uniform(1, 90, (m, 4)), rng.uniform(0, 1, m))
        )
    path = write_detections(tmp_path / "det.txt", frames)
    back = read_detections(path)
    assert [d.frame for d in back] == list(range(6))
    assert [len(d) for d in back] == [len(d) for d in frames]
    for a, b in zip(back, frames, strict=True):
        np.testing.assert_allclose(a.tlwh, b.tlwh, atol=5e-4)
        np.testing.assert_allclose(a.score, b.score, rtol=1e-5)
    # num_frames pads trailing empty frames.
    assert len(read_detections(path, num_frames=9)) == 9


def test_reader_accepts_whitespace_blank_lines_and_comments(tmp_path: Path) -> None:
    path = tmp_path / "det.txt"
    path.write_text("# header\n1 -1 1 2 3 4 0.5\n\n2, -1, 5, 6, 7, 8, 0.25\n")
    dets = read_detections(path)
    assert [len(d) for d in dets] == [1, 1]
    np.testing.assert_allclose(dets[1].tlwh, [[5, 6, 7, 8]])
    np.testing.assert_allclose(dets[0].xy, [[1 + 1.5, 2 + 2]])


def test_empty_file_gives_empty_table_and_a_warning(tmp_path: Path) -> None:
    path = tmp_path / "res.txt"
    path.write_text("# only a comment\n\n")
    with pytest.warns(InputWarning, match=r"res\.txt: the file has no rows"):
        assert len(read_tracks(path)) == 0
    with pytest.warns(InputWarning):
        assert len(read_detections(path)) == 0


def test_writer_sorts_results_by_frame_then_id(tmp_path: Path) -> None:
    rows = np.array([[2, 5, 0, 0, 1, 1], [1, 9, 0, 0, 1, 1], [2, 1, 0, 0, 1, 1]], float)
    text = (write_results(tmp_path / "r.txt", rows)).read_text().splitlines()
    assert [tuple(int(v) for v in s.split(",")[:2]) for s in text] == [(1, 9), (2, 1), (2, 5)]


GOOD = "1,-1,10,10,5,5,0.9,-1,-1,-1\n"


@pytest.mark.parametrize(
    ("kind", "bad_line", "fragment"),
    [
        ("det", "2,-1,10,10,5,5\n", "columns"),
        ("det", "2,-1,10,10,5,5,0.9,-1,-1,-1,7\n", "columns"),
        ("det", "2,-1,10,10,5,5,0.9,-1,-1\n", "columns"),
        ("det", "2,-1,ten,10,5,5,0.9,-1,-1,-1\n", "not a number"),
        ("det", "2,-1,10,nan,5,5,0.9,-1,-1,-1\n", "NaN"),
        ("det", "2,-1,10,10,inf,5,0.9,-1,-1,-1\n", "NaN or inf"),
        ("det", "2,-1,10,10,-5,5,0.9,-1,-1,-1\n", "negative width"),
        ("det", "2,-1,10,10,5,-1,0.9,-1,-1,-1\n", "negative height"),
        ("det", "0,-1,10,10,5,5,0.9,-1,-1,-1\n", "start at 1"),
        ("det", "1.5,-1,10,10,5,5,0.9,-1,-1,-1\n", "not an integer"),
        ("results", "1,2.5,10,10,5,5,0.9,-1,-1,-1\n", "id"),
    ],
)
def test_malformed_line_names_file_and_line(
    tmp_path: Path, kind: str, bad_line: str, fragment: str
) -> None:
    path = tmp_path / f"{kind}.txt"
    ok = GOOD.replace(",-1,", ",1,", 1) if kind != "det" else GOOD
    path.write_text(ok + "\n" + bad_line + ok.replace("1,", "3,", 1))
    with pytest.raises(InputError) as info:
        read_mot(path, kind)  # type: ignore[arg-type]
    message = str(info.value)
    assert message.startswith(f"{path}:3: "), message
    assert fragment in message and "\n" not in message


def test_unsorted_detection_frames_are_rejected(tmp_path: Path) -> None:
    path = tmp_path / "det.txt"
    path.write_text(GOOD.replace("1,", "2,", 1) + GOOD + GOOD)
    with pytest.raises(InputError, match=r"det\.txt:2: frames are not sorted"):
        read_detections(path)


def test_unsorted_result_frames_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "res.txt"
    path.write_text("2,1,0,0,1,1,1,-1,-1,-1\n1,1,0,0,1,1,1,-1,-1,-1\n")
    assert read_tracks(path).frame.tolist() == [1, 0]


def test_duplicate_id_in_a_frame_is_rejected(tmp_path: Path) -> None:
    path = tmp_path / "gt.txt"
    path.write_text("1,4,0,0,1,1,1,1,1\n1,5,0,0,1,1,1,1,1\n2,4,0,0,1,1,1,1,1\n1,4,3,3,1,1,1,1,1\n")
    with pytest.raises(InputError, match=r"gt\.txt:4: id 4 appears twice in frame 1"):
        read_tracks(path, kind="gt")


def test_missing_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "nope.txt"
    with pytest.raises(InputError, match=r"nope\.txt: no such file"):
        read_detections(path)


def test_failed_write_leaves_no_file(tmp_path: Path) -> None:
    rows = np.array([[1, 1, 0, 0, np.nan, 1]])
    dest = tmp_path / "res.txt"
    with pytest.raises(ValueError, match="NaN"):
        write_results(dest, rows)
    assert list(tmp_path.iterdir()) == []
