"""``mvtrack track-detections``: run the tracker on a MOTChallenge detection file."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from mvtrack.cli._options import (
    Assign,
    ConfigFile,
    Distance,
    Gate,
    MinScore,
    Predictor,
    Preset,
    ScoreHigh,
    check_choice,
    parse_gate,
    parse_optional_number,
    speed_note,
    tracker_names,
)

if TYPE_CHECKING:
    from collections.abc import Iterator

    from mvtrack.tracking import TrackerConfig
    from mvtrack.types import Detections


def results_name(detfile: Path) -> str:
    """Name of the results file for ``detfile``: ``<sequence>.txt``.

    MOTChallenge keeps detections in ``<sequence>/det/det.txt``; there the sequence folder
    names the results, otherwise the detection file's stem does.
    """
    if detfile.name == "det.txt" and detfile.parent.name == "det" and detfile.parent.parent.name:
        return f"{detfile.parent.parent.name}.txt"
    return f"{detfile.stem}.txt"


def register(app: typer.Typer) -> None:
    """Add this module's commands to ``app``."""

    @app.command("track-detections")
    def track_detections_cmd(
        detfile: Annotated[Path, typer.Argument(help="MOTChallenge detection file (det.txt).")],
        out: Annotated[
            Path,
            typer.Option(help="Folder for the results file <sequence>.txt (other files in it "
                         "are kept: the results of many sequences may share a folder)."),
        ],
        config: ConfigFile = None,
        preset: Preset = None,
        predictor: Predictor = None,
        distance: Distance = None,
        assign: Assign = None,
        gate: Gate = None,
        fps: Annotated[
            float | None,
            typer.Option(help="Frame rate of the sequence, for the time-based settings "
                         "(default: [tracker] fps of --config, else 30).", show_default=False),
        ] = None,
        coasting: Annotated[
            bool, typer.Option(help="Also write the rows of coasting (missed) tracks.")
        ] = True,
        backfill: Annotated[
            bool,
            typer.Option(
                "--backfill/--no-backfill",
                help="Write a confirmed track's rows from its first detection.",
            ),
        ] = True,
        interpolate: Annotated[
            bool,
            typer.Option(
                "--interpolate/--no-interpolate",
                help="Write the frames a track bridged without detection, interpolated (between "
                "ends each detected in the frame next to them too).",
            ),
        ] = True,
        relink: Annotated[
            bool,
            typer.Option(
                "--relink/--no-relink",
                help="Give a track that starts, alone, where an ended one was heading (within "
                "about 1.7 s) the ended one's ID.",
            ),
        ] = True,
        drop_weak: Annotated[
            bool,
            typer.Option(
                "--drop-weak/--keep-weak",
                help="Leave out a track whose detections' mean rank among the scores of all "
                "the detections the tracks took is under 0.275.",
            ),
        ] = True,
        smooth: Annotated[
            bool,
            typer.Option(
                "--smooth/--no-smooth",
                help="Write each track's positions and boxes smoothed over all its detections "
                "(Rauch-Tung-Striebel), not as the filter had them at each frame.",
            ),
        ] = True,
        score_scale: Annotated[
            str | None,
            typer.Option(
                help="How to read the detection scores: auto (rank among the scores so far, "
                "any detector), prob (probabilities in [0, 1]) or LO,HI (a linear scale). "
                "Default: the preset's (auto).",
                show_default=False,
            ),
        ] = None,
        score_high: ScoreHigh = None,
        min_score: MinScore = None,
        birth_iou: Annotated[
            str | None,
            typer.Option(
                help="A detection left over starts a track only if it overlaps no track's box "
                "by this IoU; 'none': every one does (default: the preset's, 0.3).",
                show_default=False,
            ),
        ] = None,
    ) -> None:
        """Track the detections of DETFILE and write MOTChallenge results into --out.

        Offline: a confirmed track is written from its first detection (--backfill) and the
        gaps it bridged are interpolated; a track that starts alone where an ended one was
        heading continues its ID (--relink); a track of the weakest boxes is left out
        (--drop-weak); each track's boxes are smoothed over all its detections (--smooth).
        Scores are ranked among those seen so far (auto).
        These revise earlier rows, so the results file is written once, at the end (no
        streaming, unlike mvtrack track --flush); a stretch of frames without detections is
        jumped once every track has ended.
        """
        from tqdm import tqdm

        from mvtrack.cli import _signals
        from mvtrack.config import RunSettings, check_fps, check_tracker, load_config
        from mvtrack.io.mot import read_detections
        from mvtrack.io.outdir import check_folder, make_folder
        from mvtrack.registry import ASSIGN_RULES, DISTANCES, PREDICTORS
        from mvtrack.tracking import PRESETS, track_detections
        from mvtrack.tracking.offline import frames_with_detections
        from mvtrack.video.build import build_tracker_config

        check_choice("--preset", preset, PRESETS)
        check_choice("--predictor", predictor, PREDICTORS)
        check_choice("--distance", distance, DISTANCES)
        check_choice("--assign", assign, ASSIGN_RULES)
        if fps is not None:
            check_fps("--fps", fps)
        changes: dict[str, Any] = {
            "preset": preset, "predictor": predictor, "distance": distance, "assign": assign,
            "gate": parse_gate(gate), "fps": fps,
            "score_scale": None if score_scale is None else parse_score_scale(score_scale),
            "score_high": score_high, "min_score": min_score,
            "birth_iou": None if birth_iou is None else parse_optional_number(
                "--birth-iou", birth_iou),
        }
        given = {k for k, v in changes.items() if v is not None}
        if birth_iou is not None:
            given.add("birth_iou")  # "none" (the rule off) is a value given
        # [tracker] of --config (the same file as mvtrack track's; its other tables are for
        # video runs), then the options
        table = dict(load_config(config).tracker) if config is not None else {}
        table.update({k: v for k, v in changes.items() if k in given})
        table.setdefault("fps", 30.0)
        check_folder(out)
        # the file before the tracker's settings, which are checked by building a tracker:
        # a bad file is told at once, not after a first run's half minute of compiling
        frames = read_detections(detfile)
        check_tracker(table, tracker_names(given, config))
        config_ = build_tracker_config(RunSettings(tracker=table), float(table["fps"]))
        make_folder(out)  # before the work: a folder that cannot be made stops it now
        t0 = time.perf_counter()
        bar = tqdm(total=len(frames), desc="tracking", unit="frame",
                   disable=not sys.stderr.isatty())

        def progress(items: Iterator[Detections]) -> Iterator[Detections]:
            upto = 0
            for dets in items:  # only the frames with detections: a gap advances at once
                bar.update(dets.frame + 1 - upto)
                upto = dets.frame + 1
                yield dets

        # Ctrl-C and SIGTERM end the run at a frame boundary; what was tracked is written
        with _signals.deferred() as stop:
            log = track_detections(stop.until(progress(frames_with_detections(frames))),
                                   config_, backfill_rows=backfill, interpolate=interpolate,
                                   relink=relink, drop_weak_tracks=drop_weak, smooth=smooth)
        bar.close()
        seconds = time.perf_counter() - t0
        dest = out / results_name(detfile)
        log.write_mot(dest, include_coasting=coasting)
        done = len(log)
        ms = 1000.0 * seconds / max(done, 1)
        typer.echo(
            f"{done} frames, {frames.num_detections} detections -> {log.track_ids.size} "
            f"tracks, {len(log.to_mot(coasting))} rows ({config_.predictor}, "
            f"{config_.distance}, {config_.assign}, {config_.fps:g} fps; {ms:.2f} ms/frame"
            f"{speed_note()}) "
            f"-> {dest}"
        )
        policy = output_policy(config_, coasting, backfill, interpolate, relink, drop_weak,
                               smooth)
        typer.echo(f"rows written: {policy}")
        if stop.requested:
            print(f"error: {_signals.interrupt_word()} after {done} of {len(frames)} frames; "
                  f"the tracks of those frames are in {dest}", file=sys.stderr)
            _signals.reported()
            raise typer.Exit(_signals.interrupt_status())


def parse_score_scale(text: str) -> str | tuple[float, float]:
    """``auto`` / ``prob`` as they are, ``"LO,HI"`` as a pair of numbers."""
    from mvtrack.errors import InputError
    from mvtrack.tracking.scores import check_scale

    if "," in text:
        parts = text.split(",")
        try:
            pair = tuple(float(v) for v in parts)
        except ValueError:
            raise InputError(f"--score-scale LO,HI needs two numbers, got {text!r}") from None
        value: Any = pair
    else:
        value = text.strip()
    try:
        return check_scale(value)
    except ValueError as exc:
        raise InputError(f"--score-scale {text!r}: {exc}") from None


def output_policy(config: TrackerConfig, coasting: bool, backfill: bool = True,
                  interpolate: bool = True, relink: bool = True, drop_weak: bool = True,
                  smooth: bool = True) -> str:
    """What an offline run of ``config`` writes, in one line."""
    parts = ["confirmed tracks"]
    if drop_weak:
        parts.append("but those of the weakest boxes")
    if backfill and not config.output_tentative:
        parts.append("from their first detection (backfill)")
    if relink:
        parts.append("a track that starts alone where an ended one was heading under its ID")
    if interpolate:
        parts.append("the frames they bridged interpolated")
    if smooth:
        parts.append("positions and boxes smoothed over each track")
    if coasting and config.coast_std is not None:
        parts.append("coasting rows while the prediction is within "
                     f"{config.coast_std:g} box sizes")
    if config.score_high is not None:
        scale = config.score_scale if isinstance(config.score_scale, str) else "LO,HI"
        parts.append(f"detections scored >= {config.score_high:g} ({scale} scale) matched "
                     "first")
    return ", ".join(parts)

