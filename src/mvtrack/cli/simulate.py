"""``mvtrack simulate``: write a simulated scene's ground truth, detections and video."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mvtrack.cli._options import RUN_FOLDER_HELP, Force

#: Scenes that get a video unless ``--no-video`` (the detection-level ones do not).
_VIDEO_BY_DEFAULT = ("x4", "x5", "x8")


def register(app: typer.Typer) -> None:
    """Add the ``simulate`` command to ``app``."""

    @app.command("simulate")
    def simulate_cmd(
        scene: Annotated[str, typer.Argument(help="One of: x4, x5, x7, x8, crowd.")],
        out: Annotated[Path, typer.Option(help=RUN_FOLDER_HELP)],
        seed: Annotated[int, typer.Option(help="Seed of the scene, detections and video.")] = 0,
        frames: Annotated[
            int | None,
            typer.Option(help="Frames: the crowd's length (default 300), or a shorter cut of "
                         "a fixed scene."),
        ] = None,
        n: Annotated[
            int | None, typer.Option("--n", help="Number of crowd targets (default 100).")
        ] = None,
        video: Annotated[
            bool | None,
            typer.Option("--video/--no-video",
                         help="Render video.mp4 (default: yes for x4, x5, x8; no for x7, crowd)."),
        ] = None,
        detections: Annotated[
            bool,
            typer.Option("--detections/--no-detections",
                         help="Also write det.txt: noisy detections with misses and clutter."),
        ] = False,
        force: Force = False,
    ) -> None:
        """Simulate SCENE and write gt.txt (MOTChallenge), scene.json, optionally det.txt and
        video.mp4 into --out."""
        import numpy as np

        from mvtrack.io.atomic import write_json
        from mvtrack.io.mot import write_detections, write_mot
        from mvtrack.io.outdir import run_folder
        from mvtrack.sim.detections import detections_from_scene
        from mvtrack.sim.render import write_video
        from mvtrack.sim.scenes import build

        if frames is not None and frames < 1:
            raise ValueError(f"--frames must be at least 1, got {frames}")
        if n is not None and n < 1:
            raise ValueError(f"--n must be at least 1, got {n}")
        sc = build(scene, seed=seed, frames=frames, n=n)
        with run_folder(out, force=force, kind="simulate"):
            written = [write_mot(out / "gt.txt", sc.gt_mot(), "gt")]
            if detections:
                dets = detections_from_scene(sc, np.random.default_rng([seed, 1]))
                written.append(write_detections(out / "det.txt", dets))
            if video if video is not None else scene in _VIDEO_BY_DEFAULT:
                written.append(write_video(sc, out / "video.mp4", seed=seed))
            info = {
                "scene": sc.name, "seed": seed, "fps": sc.fps, "size": list(sc.size),
                "frames": sc.n_frames, "objects": sc.n_objects,
                "category": {str(i + 1): str(c) for i, c in enumerate(sc.category)},
                "kind": {str(i + 1): str(k) for i, k in enumerate(sc.kind)},
            }
            written.append(write_json(out / "scene.json", info))
        for path in written:
            typer.echo(str(path))
