"""Reading MOTChallenge files: validated tables of rows, or detections per frame."""

from __future__ import annotations

import os
import warnings
from pathlib import Path

from mvtrack.errors import InputWarning
from mvtrack.io.mot.parse import check_rows, parse_rows
from mvtrack.io.mot.table import DetectionFrames, Kind, MotTable


def read_mot(path: str | os.PathLike[str], kind: Kind = "results") -> MotTable:
    """Read and validate a MOTChallenge text file.

    Parameters
    ----------
    path : path
        The file.
    kind : {"det", "gt", "results"}
        Its layout. Detection files must be sorted by frame; ground-truth and result files
        may come in any order but each (frame, id) pair at most once.

    Returns
    -------
    MotTable
        The rows in file order, frames 0-based. A file without rows gives an empty table and
        an :class:`~mvtrack.errors.InputWarning`.

    Raises
    ------
    InputError
        Missing or unreadable file; wrong column count; a field that is not a plain ASCII
        decimal (``1_0``, full-width digits, an empty field), NaN or inf; a frame that is not
        an integer from 1 to :data:`MAX_FRAME`; an id that is not an integer within
        ±:data:`MAX_ID`; box coordinates or sizes beyond :data:`MAX_COORD`, negative sizes;
        unsorted frames (det); a duplicate (frame, id) (gt, results). The message is
        ``<file>:<line>: <problem>``.
    """
    path = Path(path)
    values, lineno = parse_rows(path, kind)
    if values.shape[0]:
        check_rows(path, kind, values, lineno)
    else:
        warnings.warn(
            InputWarning(f"{path}: the file has no rows (it is empty or holds only comments)"),
            stacklevel=2,
        )
    return MotTable.from_rows(values)


def read_tracks(path: str | os.PathLike[str], kind: Kind = "results") -> MotTable:
    """Read a ground-truth or results file (see :func:`read_mot`)."""
    if kind == "det":
        raise ValueError("read_tracks reads gt or results files; use read_detections for det")
    return read_mot(path, kind)


def read_detections(
    path: str | os.PathLike[str], num_frames: int | None = None
) -> DetectionFrames:
    """Read a detection file as one :class:`Detections` per frame.

    Parameters
    ----------
    path : path
        A MOTChallenge ``det`` file (frame, -1, left, top, width, height, conf, ...).
    num_frames : int, optional
        Length of the sequence. Defaults to the last frame in the file.

    Returns
    -------
    DetectionFrames
        A sequence whose element ``k`` holds frame ``k`` (0-based, file frame ``k + 1``), from
        frame 0 to the last; frames without rows are empty. ``score`` is the file's
        confidence column. Frames are built when asked for: memory grows with the rows only.
    """
    table = read_mot(path, "det")
    return table.to_detections(num_frames)
