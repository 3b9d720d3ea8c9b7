"""``mvtrack track VIDEO --out DIR``: detect and track a video, write results and drawings."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path
from typing import Annotated

import typer

from mvtrack.cli._options import (
    RUN_FOLDER_HELP,
    Assign,
    ConfigFile,
    DetectorName,
    Distance,
    Force,
    Gate,
    MinScore,
    NoTemplates,
    NoVideo,
    Predictor,
    Preset,
    ScoreHigh,
    Snapshot,
    speed_note,
    video_settings,
)


def register(app: typer.Typer) -> None:
    """Add the ``track`` command to ``app``."""

    @app.command("track")
    def track_cmd(
        video: Annotated[
            str, typer.Argument(help="Video file, image folder, camera index or URL.")
        ],
        out: Annotated[Path, typer.Option(help=RUN_FOLDER_HELP)] = Path("mvtrack-out"),
        preset: Preset = None,
        predictor: Predictor = None,
        gate: Gate = None,
        distance: Distance = None,
        assign: Assign = None,
        detector: DetectorName = None,
        config: ConfigFile = None,
        score_high: ScoreHigh = None,
        min_score: MinScore = None,
        coasting: Annotated[
            bool,
            typer.Option("--coasting/--no-coasting",
                         help="Also write the rows of coasting tracks (no detection, while the "
                         "prediction is within the tracker's coast_std) to results.txt."),
        ] = False,
        offline: Annotated[
            bool,
            typer.Option("--offline/--online",
                         help="Revise the rows once the whole video is tracked: each "
                         "confirmed track written from its first detection and smoothed over "
                         "all of them (the video is then drawn in a second pass)."),
        ] = False,
        no_video: NoVideo = False,
        no_templates: NoTemplates = False,
        force: Force = False,
        max_frames: Annotated[
            int | None, typer.Option(help="Stop after this many frames.")
        ] = None,
        fps: Annotated[
            float | None,
            typer.Option(help="Frame rate to assume instead of the source's (also [tracker] fps "
                         "in --config; this option wins)."),
        ] = None,
        snapshot: Snapshot = None,
        flush: Annotated[
            float | None,
            typer.Option(
                help="Stream: append the rows of the frames tracked to results.txt and "
                "states.csv every SECONDS while the run goes on (whole lines, synced; the "
                "files are valid at every moment and end as without --flush), with memory "
                "flat on an endless stream; trajectories.png then draws the last 9000 frames.",
                metavar="SECONDS",
            ),
        ] = None,
        masks: Annotated[
            Path | None,
            typer.Option(
                help="Also write each frame's foreground as a 0/255 PNG into this folder "
                "(DIR/000001.png for the first frame; each file written atomically).",
                metavar="DIR",
            ),
        ] = None,
    ) -> None:
        """Track the moving objects of VIDEO; write results.txt (MOTChallenge), tracks.mp4,
        trajectories.png, summary.json and states.csv (every row's state, its evidence, the
        template-matching score of a stopped row and whether its box came from a plain,
        merged or split blob)
        into --out; with an [analytics] table in --config, also counts.csv, movements.csv,
        speeds.csv and tracks.csv.

        Ctrl-C stops early and still writes what was tracked (exit status 130); so does
        SIGTERM (exit status 143). With --flush SECONDS, results.txt and states.csv grow
        while the run goes on (a camera or stream can be watched, and run forever).

        --out holds one run: rerun into the same folder and the earlier run's files (video,
        snapshots, report) are replaced as a whole once the new run has finished; a folder
        holding anything else (other files, another command's run) is refused unless
        --force.
        """
        from mvtrack.cli import _signals
        from mvtrack.errors import InputError
        from mvtrack.io.outdir import run_folder
        from mvtrack.video import track_video
        from mvtrack.video.run import missed_snapshot, snapshot_frames, write_tables

        if max_frames is not None and max_frames < 1:
            raise InputError(f"--max-frames must be at least 1, got {max_frames}")
        shots = snapshot_frames(snapshot, max_frames)
        if flush is not None and not (math.isfinite(flush) and flush > 0):
            raise InputError(f"--flush must be a number of seconds > 0, got {flush:g}")
        settings = video_settings(
            config=config, preset=preset, predictor=predictor, gate=gate, distance=distance,
            assign=assign, detector=detector, no_video=no_video, no_templates=no_templates,
            score_high=score_high, min_score=min_score, fps=fps, coasting=coasting,
        )
        if offline:  # with --flush refused by track_to_folder, before any frame is read
            settings = dataclasses.replace(settings, offline=True)
        with run_folder(out, force=force, inputs=[video], kind="track"):
            run = track_video(video, out, settings, fps=settings.frame_rate,
                              max_frames=max_frames, snapshot=shots, flush=flush,
                              masks=masks)
            tables = write_tables(run, out, settings, fps=fps)
        res, summary = run.result, run.summary
        typer.echo(
            f"{summary['frames']} frames, {summary['tracks']} tracks, "
            f"{summary['processing_speed']} frames/s processed{speed_note()}; files in {out}"
        )
        for path in [*run.paths.values(), *tables.values()]:
            typer.echo(f"  {path}")
        if res.interrupted:
            print(
                f"error: {_signals.interrupt_word()} after {res.n_frames} frames; "
                f"results so far are in {out}",
                file=sys.stderr,
            )
            _signals.reported()
            raise typer.Exit(_signals.interrupt_status())
        if res.error is not None:
            raise InputError(f"{res.error}; results so far are in {out}")
        missed = missed_snapshot(run, shots, video)
        if missed:
            raise InputError(f"{missed}; the tracks are in {out}")
