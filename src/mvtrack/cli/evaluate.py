"""``mvtrack eval``: score MOTChallenge results against ground truth, one file or a folder."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

#: Rows of the printed table of one sequence: (key, label, format).
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
    ("num_ignored_gt", "GT rows ignored", "d"),
    ("num_ignored_pred", "predictions ignored", "d"),
)

#: Columns of the table of a folder: (key, header, format).
_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("MOTA", "MOTA", ".3f"),
    ("IDF1", "IDF1", ".3f"),
    ("HOTA", "HOTA", ".3f"),
    ("DetA", "DetA", ".3f"),
    ("AssA", "AssA", ".3f"),
    ("MOTP", "MOTP", ".3f"),
    ("recall", "Rcll", ".3f"),
    ("precision", "Prcn", ".3f"),
    ("IDSW", "IDsw", "d"),
    ("FP", "FP", "d"),
    ("FN", "FN", "d"),
    ("MT", "MT", "d"),
    ("ML", "ML", "d"),
    ("FM", "FM", "d"),
    ("num_gt_dets", "GT", "d"),
)

IGNORE_HELP = (
    "Ground-truth rows with flag 0 (column 7): 'drop' removes them, so a box on such a person "
    "is a false positive (the MOT15 devkit, TrackEval, motmetrics and peerbench); "
    "'distractor' also removes the predictions matched to them (the MOT16/17/20 devkit's "
    "preprocessing); 'none' scores every row."
)


def _text(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return format(value, fmt)


def format_table(scores: dict[str, Any]) -> str:
    """The scores of one sequence as a two-column text table (missing values as ``-``)."""
    width = max(len(label) for _, label, _ in _TABLE)
    lines = [f"{label:<{width}}  {_text(scores.get(key), fmt):>8}" for key, label, fmt in _TABLE]
    return "\n".join(lines)


def format_folder(rows: dict[str, dict[str, Any]], combined: dict[str, Any]) -> str:
    """One Markdown row per sequence and a combined row (summed counts)."""
    head = "| sequence | " + " | ".join(h for _, h, _ in _COLUMNS) + " |"
    rule = "|---|" + "---:|" * len(_COLUMNS)

    def row(name: str, s: dict[str, Any]) -> str:
        return f"| {name} | " + " | ".join(_text(s.get(k), f) for k, _, f in _COLUMNS) + " |"

    body = [row(name, s) for name, s in rows.items()]
    return "\n".join([head, rule, *body, row("COMBINED (summed counts)", combined)])


def _clean(scores: dict[str, Any]) -> dict[str, Any]:
    """NaN and ±inf (MOTP without matches, ...) as None: strict JSON."""
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v
            for k, v in scores.items()}


def format_analytics(acc: dict[str, Any]) -> str:
    """Count errors per movement and per line direction, and the speed accuracy, as text."""
    lines = []
    for title, key in (("movement", "movements"), ("line", "lines")):
        table = acc[key]
        keys = [k for k in table if k != "total"]
        if not keys:
            continue
        width = max(len(title), *(len(k) for k in keys))
        lines.append(f"{title:<{width}}  {'counted':>7}  {'truth':>5}  {'error':>5}")
        for k in keys:
            v = table[k]
            lines.append(f"{k:<{width}}  {v['estimated']:>7}  {v['truth']:>5}  {v['error']:>+5}")
        tot = table["total"]
        lines.append(f"{'total':<{width}}  {tot['estimated']:>7}  {tot['truth']:>5}  "
                     f"|error| {tot['abs_error']}")
        lines.append("")
    sp = acc["speed"]
    if sp is None:
        lines.append("speed: no calibration in the settings")
    else:
        lines.append(f"speed RMSE {_text(sp['rmse_kmh'], '.2f')} km/h over {sp['rows']} paired "
                     f"rows (bias {_text(sp['bias_kmh'], '+.2f')}, within 2σ "
                     f"{_text(sp['within_2sigma'], '.2f')}); rows standing still in the truth "
                     f"read as stopped: {_text(sp['stopped_read_zero'], '.2f')} of "
                     f"{sp['stopped_rows']}")
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    """Add the ``eval`` command to ``app``."""

    @app.command("eval")
    def eval_cmd(
        gt: Annotated[
            Path,
            typer.Option(help="Ground-truth file (gt.txt), or a folder of sequences "
                         "(SEQ/gt/gt.txt or SEQ/gt.txt)."),
        ],
        pred: Annotated[
            Path,
            typer.Option(help="Results file, or a folder of them (SEQ.txt, or SEQ/ holding "
                         "one .txt file)."),
        ],
        iou: Annotated[
            float, typer.Option(help="Minimum IoU for a predicted box to match a GT box.")
        ] = 0.5,
        ignore: Annotated[str, typer.Option(help=IGNORE_HELP)] = "drop",
        hota: Annotated[bool, typer.Option("--hota/--no-hota", help="Compute HOTA.")] = True,
        json: Annotated[
            Path | None, typer.Option("--json", help="Also write the scores to this JSON file.")
        ] = None,
        config: Annotated[
            Path | None,
            typer.Option("--config", help="TOML file with an [analytics] table (the one given "
                         "to mvtrack track): also count error per movement and per line, and "
                         "speed RMSE, against the ground truth's own tracks."),
        ] = None,
        fps: Annotated[
            float | None,
            typer.Option(help="Frame rate for --config (default: analytics.fps, else the "
                         "summary.json beside --pred)."),
        ] = None,
    ) -> None:
        """MOTA, MOTP, IDF1, ID switches, FP, FN, MT, ML and HOTA of MOTChallenge results.

        A folder of sequences gives one row per sequence and a combined row computed from
        the summed counts, as the MOTChallenge devkit combines sequences.
        """
        from mvtrack.errors import InputError
        from mvtrack.eval.metrics import IGNORE_MODES, score_sequence
        from mvtrack.eval.sequences import evaluate_sequences, find_sequences
        from mvtrack.io.atomic import write_json

        if not 0.0 < iou <= 1.0:
            raise InputError(f"--iou must be in (0, 1], got {iou}")
        if ignore not in IGNORE_MODES:
            raise InputError(
                f"--ignore: unknown value {ignore!r}; choose one of: {', '.join(IGNORE_MODES)}"
            )
        analytics = None
        if config is not None:
            from mvtrack.analytics import load_settings

            analytics = load_settings(config)
            if gt.is_dir() or pred.is_dir():
                raise InputError("--config scores one sequence: give --gt and --pred files")
            if fps is not None and not fps > 0:
                raise InputError(f"--fps must be positive, got {fps}")
        if gt.is_dir() or pred.is_dir():
            if not (gt.is_dir() and pred.is_dir()):
                raise InputError("--gt and --pred must both be files or both be folders")
            sequences, notes = find_sequences(gt, pred)
            per, combined = evaluate_sequences(
                sequences, iou, ignore=ignore, with_hota=hota  # type: ignore[arg-type]
            )
            for note in notes:
                typer.echo(f"warning: {note}", err=True)
            for name, s in per.items():
                for note in s.notes:
                    typer.echo(f"warning: {name}: {note}", err=True)
            rows = {name: s.as_dict() for name, s in per.items()}
            total = combined.as_dict()
            typer.echo(format_folder(rows, total))
            typer.echo(f"ignore={ignore}, IoU >= {iou:g}; combined: counts summed over "
                       f"{len(rows)} sequences, ratios computed from the sums")
            payload: dict[str, Any] = {
                "gt": str(gt), "pred": str(pred), "ignore": ignore, "iou_threshold": iou,
                "sequences": {n: _clean(s) for n, s in rows.items()},
                "combined": _clean(total),
            }
        else:
            result = score_sequence(
                gt, pred, iou, ignore=ignore, with_hota=hota  # type: ignore[arg-type]
            )
            for note in result.notes:
                typer.echo(f"warning: {note}", err=True)
            scores = result.as_dict()
            typer.echo(format_table(scores))
            payload = {"gt": str(gt), "pred": str(pred), **_clean(scores)}
            if analytics is not None:
                from mvtrack.analytics.accuracy import evaluate_analytics
                from mvtrack.analytics.run import folder_info

                rate = fps if fps is not None else analytics.fps
                if rate is None:
                    info = folder_info(pred.parent)
                    rate = info.get("video_fps") or info.get("fps_video")
                if rate is None:
                    raise InputError(f"{config}: frame rate unknown: set analytics.fps or "
                                     "pass --fps")
                acc = evaluate_analytics(gt, pred, analytics, float(rate))
                typer.echo("")
                typer.echo(format_analytics(acc))
                payload["analytics"] = acc
        if json is not None:
            write_json(json, payload)
            typer.echo(f"wrote {json}")
