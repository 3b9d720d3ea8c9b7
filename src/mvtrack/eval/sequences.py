"""A folder of sequences evaluated into one table, combined as the MOTChallenge devkit does.

Ground truth: a folder with one sub-folder per sequence, holding ``SEQ/gt/gt.txt``
(MOTChallenge layout) or ``SEQ/gt.txt`` (the layout of ``data/real``). Results: a folder with
``SEQ.txt`` per sequence (MOTChallenge layout), or ``SEQ/SEQ.txt``, or a sub-folder ``SEQ/``
holding a single ``.txt`` file (what ``mvtrack track-detections DET --out RES/SEQ`` writes).

The combined row is not the mean of the sequences' ratios: counts are summed over sequences
and the ratios computed from the sums (MOTA from the summed FN, FP and ID switches; IDF1 from
the summed IDTP; HOTA from the summed per-α TP, FN, FP with AssA weighted by TP), as the
devkit and TrackEval combine sequences.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mvtrack.errors import InputError
from mvtrack.eval.metrics import DEFAULT_IGNORE, Ignore, SequenceScores, score_sequence


@dataclass(frozen=True)
class Sequence:
    """One sequence of a folder: its name, ground truth and results."""

    name: str
    gt: Path
    results: Path


def _gt_file(folder: Path) -> Path | None:
    for candidate in (folder / "gt" / "gt.txt", folder / "gt.txt"):
        if candidate.is_file():
            return candidate
    return None


def _results_file(root: Path, name: str) -> Path | None:
    for candidate in (root / f"{name}.txt", root / name / f"{name}.txt"):
        if candidate.is_file():
            return candidate
    folder = root / name
    if folder.is_dir():
        txt = sorted(p for p in folder.iterdir() if p.suffix == ".txt" and p.is_file())
        if len(txt) == 1:
            return txt[0]
        if len(txt) > 1:
            raise InputError(
                f"{folder}: {len(txt)} .txt files ({', '.join(p.name for p in txt)}); "
                f"name the results {name}.txt"
            )
    return None


def find_sequences(
    gt_root: str | os.PathLike[str], results_root: str | os.PathLike[str]
) -> tuple[list[Sequence], list[str]]:
    """The sequences of ``gt_root`` with their results in ``results_root``.

    Returns
    -------
    sequences : list of Sequence
        Sorted by name.
    notes : list of str
        Warnings (results without ground truth).

    Raises
    ------
    InputError
        A folder is missing, holds no sequence, or a sequence has no results (as the devkit,
        which refuses a submission with a sequence missing).
    """
    gt_root, results_root = Path(gt_root), Path(results_root)
    for folder, what in ((gt_root, "ground-truth"), (results_root, "results")):
        if not folder.is_dir():
            raise InputError(f"{folder}: no such {what} folder")
    named = {p.name: _gt_file(p) for p in sorted(gt_root.iterdir()) if p.is_dir()}
    gts = {name: path for name, path in named.items() if path is not None}
    if not gts:
        raise InputError(
            f"{gt_root}: no sequence found (expected SEQ/gt/gt.txt or SEQ/gt.txt in sub-folders)"
        )
    sequences, missing = [], []
    for name, gt in gts.items():
        res = _results_file(results_root, name)
        if res is None:
            missing.append(name)
        else:
            sequences.append(Sequence(name, gt, res))
    if missing:
        raise InputError(
            f"{results_root}: no results for {len(missing)} of {len(gts)} sequences "
            f"({', '.join(missing)}); expected SEQ.txt or SEQ/ with one .txt file"
        )
    extra = sorted(
        p.stem for p in results_root.iterdir()
        if p.is_file() and p.suffix == ".txt" and p.stem not in gts
    )
    notes = [f"results without ground truth ignored: {', '.join(extra)}"] if extra else []
    return sequences, notes


def evaluate_sequences(
    sequences: list[Sequence],
    iou: float = 0.5,
    *,
    ignore: Ignore = DEFAULT_IGNORE,
    with_hota: bool = True,
) -> tuple[dict[str, SequenceScores], SequenceScores]:
    """Scores of each sequence and of their combination (summed counts).

    Raises
    ------
    InputError
        As :func:`~mvtrack.eval.metrics.score_sequence`, the message prefixed with the
        sequence's name.
    """
    if not sequences:
        raise InputError("no sequence to evaluate")
    per: dict[str, SequenceScores] = {}
    for seq in sequences:
        try:
            per[seq.name] = score_sequence(
                seq.gt, seq.results, iou, ignore=ignore, with_hota=with_hota
            )
        except InputError as exc:
            raise InputError(f"{seq.name}: {exc}") from None
    items = list(per.values())
    combined = items[0]
    for item in items[1:]:
        combined = combined + item
    return per, combined
