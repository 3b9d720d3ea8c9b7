"""``mvtrack batch VIDEO... --out DIR``: track many videos in parallel (Dask), one folder each."""

from __future__ import annotations

import dataclasses
import glob
import sys
from pathlib import Path
from typing import Annotated

import typer

from mvtrack.cli._options import (
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
    video_settings,
)

#: file extensions taken as videos when a folder is given (case-insensitive)
VIDEO_EXTENSIONS = (
    ".avi", ".mp4", ".m4v", ".mov", ".mkv", ".mpg", ".mpeg", ".wmv", ".webm", ".flv", ".3gp",
    ".ts", ".mjpeg", ".mjpg",
)

_GLOB_CHARS = frozenset("*?[")


def _folder_videos(folder: Path) -> list[str]:
    from mvtrack.io.video import IMAGE_EXTENSIONS

    files = sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    videos = [str(p) for p in files if p.suffix.lower() in VIDEO_EXTENSIONS]
    if videos:
        return videos
    if any(p.suffix.lower() in IMAGE_EXTENSIONS for p in files):
        return [str(folder)]  # an image sequence is one video
    raise ValueError(f"no videos in folder {folder} (video extensions: "
                     f"{', '.join(VIDEO_EXTENSIONS)}; or a folder of images)")


def expand_videos(args: list[str]) -> list[str]:
    """The videos named by the command-line arguments, in order, each once.

    An argument is a video file (kept even if missing: the batch reports it as failed), a
    stream URL, a glob pattern (``"clips/*.avi"``, quoted so the shell leaves it; sorted
    matches), or a folder: its video files (by :data:`VIDEO_EXTENSIONS`, sorted), or the
    folder itself when it holds images instead (an image sequence).

    Raises
    ------
    ValueError
        No arguments, a glob with no match, or a folder with no videos.
    """
    from mvtrack.video.jobs import normalise_video

    if not args:
        raise ValueError("no videos given")
    found: list[str] = []
    for arg in args:
        path = Path(arg).expanduser()
        if "://" not in arg and not path.exists() and _GLOB_CHARS & set(arg):
            matches = sorted(glob.glob(str(path), recursive=True))
            if not matches:
                raise ValueError(f"no file matches {arg!r}")
            for m in matches:
                mp = Path(m)
                found.extend(_folder_videos(mp) if mp.is_dir() else [m])
        elif path.is_dir():
            found.extend(_folder_videos(path))
        else:
            found.append(arg)
    seen: set[str] = set()
    unique = []
    for video in found:
        key = normalise_video(video)
        if key not in seen:
            seen.add(key)
            unique.append(video)
    return unique


def register(app: typer.Typer) -> None:
    """Add the ``batch`` command to ``app``."""

    @app.command("batch")
    def batch_cmd(
        videos: Annotated[
            list[str],
            typer.Argument(
                metavar="VIDEO",
                help="Video files, folders of videos, or quoted glob patterns ('clips/*.mp4')."
            ),
        ],
        out: Annotated[
            Path,
            typer.Option(help="Output folder: one sub-folder per video and batch.json. It "
                         "holds this batch only: a folder with an earlier batch is replaced "
                         "when this one finishes; a folder with anything else is refused "
                         "unless --force."),
        ],
        workers: Annotated[
            int | None,
            typer.Option(help="Local worker processes (default: the number of CPUs)."),
        ] = None,
        scheduler: Annotated[
            str | None,
            typer.Option(
                help="Address of a running Dask scheduler (tcp://host:port) whose workers see "
                "the videos and --out at the same paths; default: a local cluster."
            ),
        ] = None,
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
                         help="Also write the rows of coasting tracks to each results.txt."),
        ] = False,
        offline: Annotated[
            bool,
            typer.Option("--offline/--online",
                         help="Revise each video's rows once it is tracked, as `mvtrack track "
                         "--offline` does (the video is then drawn in a second pass)."),
        ] = False,
        no_video: NoVideo = False,
        no_templates: NoTemplates = False,
        force: Force = False,
        max_frames: Annotated[
            int | None, typer.Option(help="Track at most this many frames of each video.")
        ] = None,
        fps: Annotated[
            float | None, typer.Option(help="Frame rate to assume instead of each source's.")
        ] = None,
        snapshot: Snapshot = None,
    ) -> None:
        """Track many videos in parallel, each exactly as `mvtrack track` would, into
        --out/<video name>/; write --out/batch.json (status, frames, tracks, speed, error per
        video).

        Exit status 0 when every video succeeded, 1 when some failed (one line each on
        stderr), 2 for bad usage, 130 after Ctrl-C and 143 after SIGTERM (pending videos
        are cancelled).
        """
        from mvtrack.cli import _signals
        from mvtrack.io.outdir import run_folder
        from mvtrack.video.batch import track_many
        from mvtrack.video.run import snapshot_frames

        if workers is not None and workers < 1:
            raise ValueError(f"--workers must be at least 1, got {workers}")
        if workers is not None and scheduler is not None:
            raise ValueError("--workers sets up a local cluster; do not give it with --scheduler")
        if max_frames is not None and max_frames < 1:
            raise ValueError(f"--max-frames must be at least 1, got {max_frames}")
        shots = snapshot_frames(snapshot, max_frames)
        sources = expand_videos(videos)

        # the same settings as `mvtrack track` builds from the same options
        settings = video_settings(
            config=config, preset=preset, predictor=predictor, gate=gate, distance=distance,
            assign=assign, detector=detector, no_video=no_video, no_templates=no_templates,
            score_high=score_high, min_score=min_score, fps=fps, coasting=coasting,
        )
        if offline:
            settings = dataclasses.replace(settings, offline=True)
        with run_folder(out, force=force, inputs=sources, kind="batch"):
            items = track_many(
                sources, out, settings, workers=workers, scheduler=scheduler,
                fps=settings.frame_rate, max_frames=max_frames, snapshot=shots,
            )
        ok = [it for it in items if it.status == "ok"]
        failed = [it for it in items if it.status == "failed"]
        cancelled = [it for it in items if it.status == "cancelled"]
        typer.echo(
            f"{len(ok)} of {len(items)} videos tracked, {len(failed)} failed"
            + (f", {len(cancelled)} cancelled" if cancelled else "")
            + f"; summary in {out / 'batch.json'}"
        )
        for it in ok:
            typer.echo(f"  {it.out}: {it.frames} frames, {it.tracks} tracks, "
                       f"{it.processing_speed} frames/s")
        for it in failed:
            print(f"error: {it.video}: {it.error}", file=sys.stderr)
        if cancelled:
            print(f"error: {_signals.interrupt_word()}; {len(cancelled)} videos cancelled",
                  file=sys.stderr)
            _signals.reported()
            raise typer.Exit(_signals.interrupt_status())
        if failed:
            raise typer.Exit(1)
