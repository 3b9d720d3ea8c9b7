"""``mvtrack track VIDEO --out DIR``: detect and track a video, write results and drawings."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

_GATE_HELP = (
    "Gate on the squared distance: px² for euclidean (400 = a 20 px circle; '20px' is accepted "
    "too), a χ² value for uncoupled/coupled/mahalanobis (9.21 = 99 %), 1 − IoU for iou. "
    "Default: the preset's, else the distance's."
)


def parse_gate(text: str | None) -> float | None:
    """``"400"`` → 400.0; ``"20px"`` (a radius in pixels) → 400.0; None stays None."""
    if text is None:
        return None
    raw = text.strip().lower()
    try:
        if raw.endswith("px"):
            radius = float(raw[:-2])
            value = radius * radius
            ok = radius > 0
        else:
            value = float(raw)
            ok = value > 0
    except ValueError:
        raise ValueError(f"--gate must be a number or a radius like '20px', got {text!r}") from None
    if not ok or value != value or value == float("inf"):
        raise ValueError(f"--gate must be positive and finite, got {text!r}")
    return value


def register(app: typer.Typer) -> None:
    """Add the ``track`` command to ``app``."""

    @app.command("track")
    def track_cmd(
        video: Annotated[
            str, typer.Argument(help="Video file, image folder, camera index or URL.")
        ],
        out: Annotated[Path, typer.Option(help="Output folder.")] = Path("mvtrack-out"),
        preset: Annotated[
            str | None, typer.Option(help="Tracker preset: default, paper1, paper2.")
        ] = None,
        predictor: Annotated[
            str | None, typer.Option(help="kalman-ca, kalman-cv, kalman-coupled, rls, ...")
        ] = None,
        gate: Annotated[str | None, typer.Option(help=_GATE_HELP)] = None,
        distance: Annotated[
            str | None,
            typer.Option(help="euclidean, uncoupled, coupled, coupled-literal, mahalanobis, iou"),
        ] = None,
        assign: Annotated[str | None, typer.Option(help="nearest, greedy, optimal")] = None,
        detector: Annotated[
            str | None, typer.Option(help="disturbance-map (default), frame-diff, mog2")
        ] = None,
        config: Annotated[
            Path | None, typer.Option(help="TOML settings file (see mvtrack.config).")
        ] = None,
        no_video: Annotated[
            bool, typer.Option("--no-video", help="Skip the annotated MP4 (faster).")
        ] = False,
        no_templates: Annotated[
            bool,
            typer.Option("--no-templates", help="No template matching for stopped vehicles."),
        ] = False,
        max_frames: Annotated[
            int | None, typer.Option(help="Stop after this many frames.")
        ] = None,
        fps: Annotated[
            float | None, typer.Option(help="Frame rate to assume instead of the source's.")
        ] = None,
        snapshot: Annotated[
            int | None,
            typer.Option(help="Also save the annotated frame N (0-based) as frameNNNNN.png."),
        ] = None,
    ) -> None:
        """Track the moving objects of VIDEO; write results.txt (MOTChallenge), tracks.mp4,
        trajectories.png and summary.json into --out.

        Ctrl-C stops early and still writes what was tracked (exit status 130).
        """
        import dataclasses

        from mvtrack.config import DETECTORS, RunSettings, load_config
        from mvtrack.errors import InputError
        from mvtrack.io.video import open_source
        from mvtrack.pipeline import (
            build_detector,
            build_tracker,
            resolve_settings,
            track_to_folder,
        )

        if max_frames is not None and max_frames < 1:
            raise ValueError(f"--max-frames must be at least 1, got {max_frames}")
        if snapshot is not None and snapshot < 0:
            raise ValueError(f"--snapshot must be a frame index >= 0, got {snapshot}")
        settings = load_config(config) if config is not None else RunSettings()
        settings = settings.with_overrides(
            preset=preset, predictor=predictor, gate=parse_gate(gate), distance=distance,
            assign=assign,
        )
        if detector is not None:
            if detector not in DETECTORS:
                raise InputError(
                    f"--detector {detector!r} is not a detector (choose one of: "
                    f"{', '.join(DETECTORS)})"
                )
            params = settings.detector_params if detector == settings.detector else {}
            settings = dataclasses.replace(settings, detector=detector, detector_params=params)
        if no_video:
            settings = dataclasses.replace(settings, video=False)
        if no_templates:
            settings = dataclasses.replace(settings, templates=False)

        # Everything that can be wrong with the input fails here, before any file is written.
        src = open_source(video, fps=fps)
        with src:
            settings = resolve_settings(settings, src.size)
            parts = (build_detector(settings), build_tracker(settings, src.fps))
            run = track_to_folder(
                (frame for _, frame in src), fps=src.fps, size=src.size, settings=settings,
                out=out, max_frames=max_frames, total=src.frame_count, source=str(video),
                parts=parts, source_error=lambda: src.error, snapshot=snapshot,
            )
        res, summary = run.result, run.summary
        typer.echo(
            f"{summary['frames']} frames, {summary['tracks']} tracks, "
            f"{summary['fps']} fps; files in {out}"
        )
        for path in run.paths.values():
            typer.echo(f"  {path}")
        if res.interrupted:
            print(
                f"error: interrupted after {res.n_frames} frames; results so far are in {out}",
                file=sys.stderr,
            )
            raise typer.Exit(130)
        if res.error is not None:
            raise InputError(f"{res.error}; results so far are in {out}")
