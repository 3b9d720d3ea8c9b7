"""``mvtrack demo``: render the X5 intersection, track it, score it, leave the files."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from mvtrack.cli._options import Force, speed_note


def run_demo(
    out: Path, *, frames: int | None = None, seed: int = 0, video: bool = True,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Render X5 (SPEC §5), track it with the default settings, score it; return the figures.

    Writes into ``out``: ``tracks.mp4`` (annotated), ``results.txt`` and ``gt.txt``
    (MOTChallenge), ``trajectories.png``, ``track_lengths.png``, ``tracks_per_frame.png``,
    ``summary.json`` (the run) and ``metrics.json`` (MOTA, IDF1, ... against the truth).
    """
    from mvtrack.config import RunSettings
    from mvtrack.eval.metrics import evaluate
    from mvtrack.io.atomic import write_json
    from mvtrack.io.mot import MotTable, write_mot
    from mvtrack.sim.intersection import x5_intersection
    from mvtrack.sim.render import render_frames
    from mvtrack.video import build_detector, build_tracker, resolve_settings, track_to_folder
    from mvtrack.viz.plots import (
        TrackRows,
        save_figure,
        track_length_figure,
        tracks_per_frame_figure,
    )

    scene = x5_intersection(seed)
    if frames is not None:
        scene = scene.truncate(frames)
    # paper 1's front end, whatever the default of mvtrack track: the demo is paper 1's system
    settings = resolve_settings(RunSettings(video=video, detector="disturbance-map"),
                                scene.size, scene.fps)
    parts = (build_detector(settings), build_tracker(settings, scene.fps))
    run = track_to_folder(
        render_frames(scene, seed), fps=scene.fps, size=scene.size, settings=settings, out=out,
        total=scene.n_frames, source=f"x5_intersection(seed={seed})", progress=progress,
        parts=parts,
    )
    gt = MotTable.from_rows(scene.gt_mot())
    pred = MotTable.from_rows(run.log.to_mot(include_coasting=False))  # = results.txt
    metrics = evaluate(gt, pred, with_hota=False)
    write_mot(out / "gt.txt", gt, "gt")
    rows = TrackRows.from_frames(run.log)
    save_figure(track_length_figure(rows, scene.fps, "X5 demo: track lengths"),
                out / "track_lengths.png")
    save_figure(tracks_per_frame_figure(rows, run.result.n_frames, "X5 demo: tracks per frame"),
                out / "tracks_per_frame.png")
    keep = ("MOTA", "MOTP", "IDF1", "IDSW", "FP", "FN", "MT", "ML")
    figures = {k: metrics[k] for k in keep if k in metrics}
    figures |= {
        "frames": run.result.n_frames,
        "vehicles": len(set(scene.id[scene.visible].tolist())),
        "tracks": run.summary["tracks"],
        "processing_speed": run.summary["processing_speed"],
        "seed": seed,
    }
    write_json(out / "metrics.json", figures)
    return figures


def register(app: typer.Typer) -> None:
    """Add the ``demo`` command to ``app``."""

    @app.command("demo")
    def demo_cmd(
        out: Annotated[
            Path,
            typer.Option(help="Folder for the video, plots and results. It holds this run "
                         "only: a folder with an earlier demo is replaced when this one "
                         "finishes; a folder with anything else is refused unless --force."),
        ] = Path("mvtrack-demo"),
        frames: Annotated[
            int | None, typer.Option(help="Use only the first N of the 360 frames.")
        ] = None,
        seed: Annotated[int, typer.Option(help="Seed of the scene and its rendering.")] = 0,
        no_video: Annotated[
            bool, typer.Option("--no-video", help="Skip the annotated MP4.")
        ] = False,
        force: Force = False,
    ) -> None:
        """Render a synthetic intersection (paper 1's X5), track it with the defaults, score it
        against its ground truth and leave the annotated video and plots in --out."""
        if frames is not None and not 2 <= frames <= 360:
            raise ValueError(f"--frames must be in 2..360, got {frames}")
        from mvtrack.io.outdir import run_folder

        with run_folder(out, force=force, kind="demo"):
            f = run_demo(out, frames=frames, seed=seed, video=not no_video)
        typer.echo(
            f"mvtrack demo: synthetic intersection (X5), {f['frames']} frames, "
            f"{f['vehicles']} vehicles"
        )
        typer.echo(
            f"  tracks {f['tracks']}   MOTA {f['MOTA']:.3f}   IDF1 {f['IDF1']:.3f}   "
            f"ID switches {f['IDSW']}   {f['processing_speed']} frames/s (detect, track, draw)"
            f"{speed_note()}"
        )
        names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
        typer.echo(f"  files in {out}: {', '.join(names)}")
