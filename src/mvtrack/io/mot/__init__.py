"""MOTChallenge text files: detections, ground truth and tracker results.

One row per box, comma separated (whitespace is accepted too), frames 1-based in the file:

=========  ====================================================================
kind       columns
=========  ====================================================================
``det``    frame, -1, left, top, width, height, conf, x, y, z
``gt``     frame, id, left, top, width, height, conf/flag, class, visibility
``results``frame, id, left, top, width, height, conf, -1, -1, -1
=========  ====================================================================

Inside mvtrack frame indices are 0-based (``Detections.frame``, ``MotTable.frame``); the
readers subtract one and the writers add it back.

Files are parsed in one vectorised pass (``np.loadtxt``); every check then runs on whole
columns, and a failure raises :class:`~mvtrack.errors.InputError` with a one-line message
``<file>:<line>: <problem>`` naming the first offending line of the file. Numbers are plain
ASCII decimals (``12``, ``-0.5``, ``1e3``); anything else (``1_0``, full-width digits, an
empty field, ``nan``, ``inf``) is refused with the same kind of message, and so are values out
of range (:data:`MAX_FRAME`, :data:`MAX_ID`, :data:`MAX_COORD`).

Memory grows with the rows of a file, never with its largest frame number: the per-frame
views (:class:`FrameIndex`, :class:`DetectionFrames`) build a frame when it is asked for.

One concept a module: :mod:`~mvtrack.io.mot.table` (the rows and the per-frame views),
:mod:`~mvtrack.io.mot.parse` (text to checked rows, the error messages),
:mod:`~mvtrack.io.mot.read` and :mod:`~mvtrack.io.mot.write`.
"""

from __future__ import annotations

from mvtrack.io.mot.parse import MAX_COORD, MAX_FRAME, MAX_ID
from mvtrack.io.mot.read import read_detections, read_mot, read_tracks
from mvtrack.io.mot.table import KINDS, DetectionFrames, FrameIndex, Kind, MotTable
from mvtrack.io.mot.write import format_rows, write_detections, write_mot, write_results

__all__ = [
    "KINDS",
    "MAX_COORD",
    "MAX_FRAME",
    "MAX_ID",
    "DetectionFrames",
    "FrameIndex",
    "Kind",
    "MotTable",
    "format_rows",
    "read_detections",
    "read_mot",
    "read_tracks",
    "write_detections",
    "write_mot",
    "write_results",
]
