"""MOTChallenge readers under fuzzing: any text either reads or raises the project's own error.

Hypothesis writes detection, ground-truth and results files made of plausible rows, rows with
one field broken, and arbitrary text or bytes. Whatever comes in, the readers must return a
table whose values are in range, or raise :class:`InputError` with one line naming the file
(and the line, which must exist); no other exception and no NumPy warning may escape. Values
the readers accept must be exactly those Python's ``float`` reads from the same fields, and
files the writers produce must read back unchanged.
"""

from __future__ import annotations

import os
import re
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mvtrack.errors import InputError, InputWarning
from mvtrack.io.mot import (
    MAX_COORD,
    MAX_FRAME,
    MAX_ID,
    FrameIndex,
    MotTable,
    read_detections,
    read_mot,
    write_detections,
    write_mot,
)

#: Examples per test; MVTRACK_FUZZ_EXAMPLES=5000 for a longer hunt.
EXAMPLES = int(os.environ.get("MVTRACK_FUZZ_EXAMPLES", "60"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=os.environ.get("CI", "").lower() == "true",  # the same examples on every CI run
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
KINDS = ("det", "gt", "results")

#: Fields that are numbers, fields that only look like numbers, and ones that are not at all.
ODD_TOKENS = [
    "1", "-1", "0", "2", "10", "0.5", "1e3", "-0.0", "+3", ".5", "5.", "1E2", "00012",
    "1_0", "２", "١", "¹", "½", "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "", " ",
    "1e20", "-1e20", "1e999", "-1e999", "1e-400", "9007199254740993", "1e16", "1e7", "1e6",
    "0x10", "#", "e5", "1e", "--1", "1.2.3", "\u00a0", "\x00", "abc", "1,5", "\ufeff1", "−1",
    "10000000", "10000001", "1000000.5", "1000000", "1000000.001", "-1000000.001",
    "9007199254740991", "9007199254740992", "-9007199254740992",
]
tokens = st.one_of(
    st.sampled_from(ODD_TOKENS),
    st.integers(-(10**20), 10**20).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(max_size=4),
)


def _valid_row(kind: str) -> st.SearchStrategy[list[str]]:
    """Fields of a row that a reader must accept (before any mutation)."""
    n = st.integers(7 if kind == "det" else 6, 10)
    coord = st.integers(-10**6, 10**6).map(lambda k: f"{k / 1000:.3f}")
    size = st.integers(0, 10**6).map(lambda k: f"{k / 1000:.3f}")
    return st.tuples(
        st.integers(1, 40).map(str),
        st.just("-1") if kind == "det" else st.integers(1, 6).map(str),
        coord, coord, size, size,
        st.lists(st.integers(-5, 5).map(str), min_size=4, max_size=4),
        n,
    ).map(lambda t: [*t[:6], *t[6]][: t[7]])


def _text(kind: str) -> st.SearchStrategy[str]:
    """A file: valid rows, some with one field replaced, formatted in the ways files come."""

    @st.composite
    def build(draw: st.DrawFn) -> str:
        rows = draw(st.lists(_valid_row(kind), max_size=6))
        if kind == "det":
            rows.sort(key=lambda r: int(r[0]))
        for _ in range(draw(st.integers(0, 3)) if rows else 0):  # break up to three fields
            i = draw(st.integers(0, len(rows) - 1))
            j = draw(st.integers(0, len(rows[i]) - 1))
            rows[i][j] = draw(st.sampled_from(ODD_TOKENS) | tokens)
        if draw(st.booleans()):  # arbitrary rows of arbitrary fields
            rows += draw(st.lists(st.lists(tokens, max_size=11), max_size=3))
        sep = draw(st.sampled_from([",", ", ", " ", "\t", " , "]))
        end = draw(st.sampled_from(["\n", "\r\n"]))
        lines = [sep.join(r) for r in rows]
        if draw(st.booleans()):
            lines.insert(draw(st.integers(0, len(lines))), draw(st.sampled_from(["", "# c", "  "])))
        head = draw(st.sampled_from(["", "\ufeff"]))
        return head + end.join(lines) + draw(st.sampled_from(["", end]))

    return build()


def _reference(text: str) -> list[list[float]]:
    """What the fields mean, read the plain way (for files the reader accepted)."""
    rows = []
    for line in text.lstrip("\ufeff").splitlines():
        s = line.strip(" \t")
        if not s or s.startswith("#"):
            continue
        fields = re.split(r"[ \t]*,[ \t]*|[ \t]+", s)
        rows.append([float(t) for t in fields])
    return rows


def _read(path: Path, kind: str) -> MotTable | None:
    """Read as ``kind``; None for an InputError (checked to be one line naming the file)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a NumPy cast or overflow warning is a bug
        warnings.simplefilter("ignore", InputWarning)
        try:
            if kind == "det":
                frames = read_detections(path)
                assert len(frames) == frames.table.num_frames
                return frames.table
            return read_mot(path, kind)  # type: ignore[arg-type]
        except InputError as exc:
            message = str(exc)
            assert "\n" not in message and message.startswith(f"{path}:"), message
            line = re.match(rf"{re.escape(str(path))}:(\d+): ", message)
            if line:
                n_lines = len(path.read_bytes().split(b"\n"))
                assert 1 <= int(line.group(1)) <= n_lines, message
            return None


def _assert_in_range(table: MotTable, kind: str) -> None:
    assert np.all((table.frame >= 0) & (table.frame < MAX_FRAME))
    assert np.all(np.abs(table.id) <= MAX_ID)
    assert np.isfinite(table.tlwh).all() and np.isfinite(table.conf).all()
    assert np.all(np.abs(table.tlwh) <= MAX_COORD) and np.all(table.tlwh[:, 2:] >= 0)
    if kind == "det":
        assert np.all(np.diff(table.frame) >= 0)
    else:
        pairs = np.unique(np.column_stack([table.frame, table.id]), axis=0)
        assert pairs.shape[0] == len(table)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@pytest.mark.parametrize("kind", KINDS)
@FUZZ
@given(data=st.data())
def test_any_text_reads_in_range_or_fails_with_one_line(
    workdir: Path, kind: str, data: st.DataObject
) -> None:
    text = data.draw(_text(kind))
    path = workdir / f"{kind}.txt"
    path.write_text(text, encoding="utf-8")
    table = _read(path, kind)
    if table is None:
        return
    _assert_in_range(table, kind)
    ref = _reference(text)
    assert len(table) == len(ref)
    if ref:
        rows = np.array(ref)
        np.testing.assert_array_equal(table.frame, rows[:, 0] - 1)
        np.testing.assert_array_equal(table.tlwh, rows[:, 2:6])
        if kind != "det":
            np.testing.assert_array_equal(table.id, rows[:, 1])


@pytest.mark.parametrize("kind", KINDS)
@FUZZ
@given(raw=st.binary(max_size=300))
def test_any_bytes_read_or_fail_with_one_line(workdir: Path, kind: str, raw: bytes) -> None:
    path = workdir / f"{kind}.bin"
    path.write_bytes(raw)
    table = _read(path, kind)
    if table is not None:
        _assert_in_range(table, kind)


def _table(kind: str, last: int = MAX_FRAME - 1) -> st.SearchStrategy[MotTable]:
    """Valid tables at the writers' precision (3 decimals for boxes, 6 digits for the rest)."""

    @st.composite
    def build(draw: st.DrawFn) -> MotTable:
        k = draw(st.integers(0, 30))
        frame = np.array(draw(st.lists(st.integers(0, last), min_size=k, max_size=k)))
        if kind == "det":
            ids = np.full(k, -1)
        else:
            ids = np.array(draw(st.lists(
                st.integers(-MAX_ID, MAX_ID), min_size=k, max_size=k, unique=True
            )), dtype=np.int64)
        milli = st.integers(-(10**9), 10**9).map(lambda v: v / 1000)
        size = st.integers(0, 10**9).map(lambda v: v / 1000)
        six = st.integers(0, 10**6).map(lambda v: v / 10**6)
        boxes = [draw(st.tuples(milli, milli, size, size)) for _ in range(k)]
        return MotTable(
            frame.astype(np.int64).reshape(-1), ids.reshape(-1),
            np.array(boxes, dtype=np.float64).reshape(-1, 4),
            np.array(draw(st.lists(six, min_size=k, max_size=k))),
            np.array(draw(st.lists(st.integers(-1, 12), min_size=k, max_size=k)), np.int64)
            if kind == "gt" else np.full(k, -1),
            np.array(draw(st.lists(six, min_size=k, max_size=k)))
            if kind == "gt" else np.full(k, -1.0),
        )

    return build()


@pytest.mark.parametrize("kind", KINDS)
@settings(FUZZ, max_examples=max(EXAMPLES // 4, 10))
@given(data=st.data())
def test_written_files_read_back_unchanged(workdir: Path, kind: str, data: st.DataObject) -> None:
    table = data.draw(_table(kind))
    path = write_mot(workdir / f"rt-{kind}.txt", table, kind)  # type: ignore[arg-type]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", InputWarning)
        back = read_mot(path, kind)  # type: ignore[arg-type]
    keys = (table.frame,) if kind == "det" else (table.id, table.frame)
    want = table.take(np.lexsort(keys))
    for name in ("frame", "id", "tlwh", "conf", "cls", "visibility"):
        np.testing.assert_array_equal(getattr(back, name), getattr(want, name), err_msg=name)


@settings(FUZZ, max_examples=max(EXAMPLES // 4, 10))
@given(data=st.data())
def test_detection_frames_round_trip_through_a_det_file(
    workdir: Path, data: st.DataObject
) -> None:
    table = data.draw(_table("det", last=data.draw(st.sampled_from([5, 50, MAX_FRAME - 1]))))
    frames = table.to_detections()
    as_list = list(frames) if len(frames) <= 50 else frames  # the eager form writes the same
    path = write_detections(workdir / "rt-frames.txt", as_list)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        back = read_detections(path, num_frames=len(frames))
    assert len(back) == len(frames) and back.num_detections == len(table)
    for f, rows in back.index.groups():
        np.testing.assert_allclose(back[f].tlwh, frames[f].tlwh, atol=1e-6)
        np.testing.assert_array_equal(back[f].score, frames[f].score)
        assert rows.size == len(frames[f])


@settings(FUZZ, max_examples=2 * EXAMPLES)
@given(
    frames=st.lists(st.integers(-3, 25), max_size=40),
    n=st.integers(0, 30),
)
def test_frame_index_equals_the_list_it_stands_for(frames: list[int], n: int) -> None:
    frame = np.array(frames, dtype=np.int64)
    naive = [np.flatnonzero(frame == f) for f in range(n)]  # file order within a frame
    index = FrameIndex(frame, n)
    assert len(index) == n
    assert [a.tolist() for a in index] == [a.tolist() for a in naive]
    assert [index[f].tolist() for f in range(n)] == [a.tolist() for a in naive]
    assert [index[f - n].tolist() for f in range(n)] == [a.tolist() for a in naive]
    assert [a.tolist() for a in index[1::2]] == [a.tolist() for a in naive[1::2]]
    assert [(f, a.tolist()) for f, a in index.groups()] == [
        (f, a.tolist()) for f, a in enumerate(naive) if a.size
    ]
    assert index.num_rows == sum(a.size for a in naive)
    for bad in (n, -n - 1):
        with pytest.raises(IndexError):
            index[bad]


def test_memory_grows_with_rows_not_with_the_last_frame(tmp_path: Path) -> None:
    """Two rows, last frame 200 000: the old per-frame list cost ~0.5 KB a frame (~100 MB)."""
    path = tmp_path / "det.txt"
    path.write_text("1,-1,10,10,20,40,0.9\n200000,-1,12,10,20,40,0.8\n")
    tracemalloc.start()
    try:
        frames = read_detections(path)
        last, middle = frames[-1], frames[100_000]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(frames) == 200_000 and frames.num_detections == 2
    assert last.frame == 199_999 and len(last) == 1 and len(middle) == 0
    np.testing.assert_allclose(last.tlwh, [[12, 10, 20, 40]])
    assert peak < 1_000_000, f"peak {peak} bytes"
