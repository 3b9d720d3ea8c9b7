"""Parsing MOTChallenge text, with a one-line error naming the file and line.

Files are parsed in one vectorised pass (``np.loadtxt``); every check then runs on whole
columns, and a failure raises :class:`~mvtrack.errors.InputError` with the message
``<file>:<line>: <problem>`` naming the first offending line. Values out of range
(:data:`MAX_FRAME`, :data:`MAX_ID`, :data:`MAX_COORD`) are refused the same way.
"""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mvtrack.errors import InputError
from mvtrack.io.mot.table import KINDS
from mvtrack.types import FloatArray, IntArray

#: Accepted column counts per kind (the trailing columns are optional).
_NCOLS: dict[str, tuple[int, int]] = {"det": (7, 10), "gt": (6, 10), "results": (6, 10)}

#: Largest frame number a file may hold (1-based): about 3.9 days at 30 fps. Longer
#: recordings are split into sequences; the cap keeps a typo such as ``1e9`` from sending a
#: per-frame consumer (the tracker, the metrics) through a billion empty frames.
MAX_FRAME = 10_000_000
#: Largest magnitude of an ID (and of columns 8 to 10): the integers that float64, in which
#: files are parsed, represents exactly. Beyond it distinct IDs would collapse into one.
MAX_ID = 2**53 - 1
#: Largest magnitude of a box coordinate, width or height, in pixels.
MAX_COORD = 1e6

_SEP = re.compile(r"[ \t]*,[ \t]*|[ \t]+")
#: A character that cannot appear in rows of plain ASCII decimals sends the text to the
#: token-by-token check, which names the first bad field (``np.loadtxt`` alone would accept
#: ``nan`` and ``inf``, and reports other failures without the file's line number).
_NOT_PLAIN = re.compile(r"[^0-9eE+\-.,\n]")
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)


def _fail(path: Path, line: int, problem: str) -> InputError:
    return InputError(f"{path}:{line}: {problem}")


def _num(value: float) -> str:
    """A parsed value as a user would write it: ``12``, ``2.5``, ``1e+20``."""
    if value.is_integer() and abs(value) < 1e16:
        return str(int(value))
    return repr(float(value))


def _read_text(path: Path) -> str:
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if not path.is_file():
        raise InputError(f"{path}: not a file")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a text file ({exc.reason} at byte {exc.start})") from None


def _bad_token(token: str) -> str | None:
    """Why ``token`` is not a plain ASCII decimal, or None when it is one."""
    if _NUMBER.fullmatch(token):
        return None
    if not token:
        return "is empty"
    if _NON_FINITE.fullmatch(token):
        return f"is {token} (NaN or inf)"
    hint = "" if token.isascii() else " (numbers are written with ASCII digits)"
    return f"is not a number: {token!r}{hint}"


def parse_rows(path: Path, kind: str) -> tuple[FloatArray, IntArray]:
    """Numeric rows of ``path`` and the 1-based file line number of each row."""
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    text = _read_text(path)
    lines = text.split("\n")
    if text.endswith("\n"):
        lines.pop()
    if "\r" in text:  # CRLF line ends
        lines = [s.rstrip("\r") for s in lines]
    if " " in text or "\t" in text:  # whitespace-separated (or padded) columns
        lines = [_SEP.sub(",", s.strip(" \t")) for s in lines]
    keep = [i for i, s in enumerate(lines) if s and not s.startswith("#")]
    lineno = np.asarray(keep, dtype=np.int64) + 1
    if not keep:
        return np.zeros((0, 10)), lineno
    body = lines if len(keep) == len(lines) else [lines[i] for i in keep]
    ncols = np.fromiter((s.count(",") + 1 for s in body), dtype=np.int64, count=len(body))
    lo, hi = _NCOLS[kind]
    bad = np.flatnonzero((ncols < lo) | (ncols > hi))
    if bad.size:
        i = bad[0]
        raise _fail(
            path, lineno[i], f"expected {lo} to {hi} columns for a {kind} file, found {ncols[i]}"
        )
    bad = np.flatnonzero(ncols != ncols[0])
    if bad.size:
        i = bad[0]
        raise _fail(
            path, lineno[i], f"found {ncols[i]} columns, but line {lineno[0]} has {ncols[0]}"
        )
    joined = "\n".join(body)
    if not _NOT_PLAIN.search(joined):
        try:
            values = np.loadtxt(
                io.StringIO(joined), delimiter=",", ndmin=2, comments=None, dtype=np.float64
            )
        except ValueError:
            pass  # a malformed field of plain characters ("", "1e", "--1"): find it below
        else:
            return values, lineno
    # Field by field, only when the fast path cannot vouch for every one.
    for i, s in enumerate(body):
        for col, token in enumerate(s.split(","), start=1):
            why = _bad_token(token)
            if why is not None:
                raise _fail(path, lineno[i], f"column {col} {why}")
    return np.array([[float(t) for t in s.split(",")] for s in body]), lineno


def check_rows(path: Path, kind: str, values: FloatArray, lineno: IntArray) -> None:
    """Column-wise validation; raises on the first offending line of the file."""
    finite = np.isfinite(values)
    if not finite.all():  # only from overflow ("1e999"): the parser refuses "nan" and "inf"
        row = int(np.flatnonzero(~finite.all(axis=1))[0])
        col = int(np.flatnonzero(~finite[row])[0])
        raise _fail(path, lineno[row], f"column {col + 1} is {values[row, col]} (NaN or inf)")
    problems: list[tuple[int, str]] = []  # (row, message): the first hit of each check

    def check(mask: NDArray[np.bool_], col: int, problem: str) -> None:
        hit = np.flatnonzero(mask)
        if hit.size:
            row = int(hit[0])
            problems.append((row, problem.format(v=_num(float(values[row, col])))))

    frame = values[:, 0]
    check(frame != np.round(frame), 0, "frame (column 1) is {v}, not an integer")
    check(frame < 1, 0, "frame (column 1) is {v}; MOTChallenge frames start at 1")
    check(frame > MAX_FRAME, 0, f"frame (column 1) is {{v}}, above the limit of {MAX_FRAME}")
    ids = values[:, 1]  # -1 in detection files
    check(ids != np.round(ids), 1, "id (column 2) is {v}, not an integer")
    check(np.abs(ids) > MAX_ID, 1, f"id (column 2) is {{v}}, beyond ±{MAX_ID}")
    for col, name in ((2, "left"), (3, "top")):
        check(
            np.abs(values[:, col]) > MAX_COORD, col,
            f"{name} (column {col + 1}) is {{v}}, beyond ±{MAX_COORD:.0e} pixels",
        )
    for col, name in ((4, "width"), (5, "height")):
        check(values[:, col] < 0, col, f"negative {name} (column {col + 1}): {{v}}")
        check(
            values[:, col] > MAX_COORD, col,
            f"{name} (column {col + 1}) is {{v}}, above {MAX_COORD:.0e} pixels",
        )
    for col in range(7, values.shape[1]):
        check(np.abs(values[:, col]) > MAX_ID, col, f"column {col + 1} is {{v}}, beyond ±{MAX_ID}")
    if kind == "det":
        back = np.flatnonzero(np.diff(frame) < 0)
        if back.size:
            row = int(back[0]) + 1
            problems.append((
                row,
                f"frames are not sorted (frame {_num(frame[row])} after {_num(frame[row - 1])})",
            ))
    if problems:
        row, message = min(problems)
        raise _fail(path, lineno[row], message)
    if kind != "det":
        # Each (frame, id) at most once.
        order = np.lexsort((values[:, 1], frame))
        dup = (np.diff(frame[order]) == 0) & (np.diff(values[order, 1]) == 0)
        if dup.any():
            rows = order[1:][dup]
            row = rows[np.argmin(lineno[rows])]
            raise _fail(
                path, lineno[row],
                f"id {int(values[row, 1])} appears twice in frame {int(frame[row])}",
            )
