"""``mvtrack eval``: score a MOTChallenge results file against ground truth."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

#: Rows of the printed table: (key, label, format).
_TABLE: tuple[tuple[str, str, str], ...] = (
    ("MOTA", "MOTA", ".3f"),
    ("MOTP", "MOTP (mean IoU)", ".3f"),
    ("IDF1", "IDF1", ".3f"),
    ("IDP", "IDP", ".3f"),
    ("IDR", "IDR", ".3f"),
    ("HOTA", "HOTA", ".3f"),
    ("DetA", "DetA", ".3f"),
    ("AssA", "AssA", ".3f"),
    ("LocA", "LocA", ".3f"),
    ("precision", "precision", ".3f"),
    ("recall", "recall", ".3f"),
    ("IDSW", "ID switches", "d"),
    ("FP", "FP", "d"),
    ("FN", "FN", "d"),
    ("MT", "MT", "d"),
    ("PT", "PT", "d"),
    ("ML", "ML", "d"),
    ("FM", "fragmentations", "d"),
    ("num_gt_ids", "GT ids", "d"),
    ("num_pred_ids", "predicted ids", "d"),
    ("num_gt_dets", "GT boxes", "d"),
    ("num_pred_dets", "predicted boxes", "d"),
)


def format_table(scores: dict[str, Any]) -> str:
    """The scores as a two-column text table (missing values shown as ``-``)."""
    width = max(len(label) for _, label, _ in _TABLE)
    lines = []
    for key, label, fmt in _TABLE:
        value = scores.get(key)
        text = "-" if value is None else format(value, fmt)
        lines.append(f"{label:<{width}}  {text:>8}")
    lines.extend(f"note: {note}" for note in scores.get("notes", []))
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    """Add the ``eval`` command to ``app``."""

    @app.command("eval")
    def eval_cmd(
        gt: Annotated[Path, typer.Option(help="Ground-truth MOTChallenge file (gt.txt).")],
        pred: Annotated[Path, typer.Option(help="Tracker results MOTChallenge file.")],
        iou: Annotated[
            float, typer.Option(help="Minimum IoU for a predicted box to match a GT box.")
        ] = 0.5,
        json: Annotated[
            Path | None, typer.Option("--json", help="Also write the scores to this JSON file.")
        ] = None,
    ) -> None:
        """MOTA, MOTP, IDF1, ID switches, FP, FN, MT, ML (motmetrics) and HOTA (TrackEval)."""
        from mvtrack.eval.metrics import evaluate
        from mvtrack.io.atomic import write_json

        if not 0.0 < iou <= 1.0:
            raise ValueError(f"--iou must be in (0, 1], got {iou}")
        scores = evaluate(gt, pred, iou)
        typer.echo(format_table(scores))
        if json is not None:
            # NaN and ±inf (e.g. MOTP without matches, MOTA without GT boxes) are not JSON.
            clean = {k: None if isinstance(v, float) and not math.isfinite(v) else v
                     for k, v in scores.items()}
            write_json(json, {"gt": str(gt), "pred": str(pred), **clean})
            typer.echo(f"wrote {json}")
