"""``mvtrack analyze OUTDIR`` and ``mvtrack report OUTDIR``: traffic analytics on an existing
output folder (``results.txt`` of ``mvtrack track``), with the settings of
:func:`mvtrack.analytics.defaults.choose_settings`."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

Settings = Annotated[
    Path | None,
    typer.Option("--config", help="TOML file with an [analytics] table (lines, zones, "
                 "approaches, calibration, interval); see docs/analytics-example.toml. "
                 "Default: the settings of the folder's earlier analysis (analytics.json), "
                 "else the [analytics] table the run was tracked with; without lines, zones "
                 "or approaches, every track's origin and destination at the image border "
                 "and counts through the middle of the image."),
]
Fps = Annotated[float | None, typer.Option(help="Frame rate (default: summary.json).")]


def _run(outdir: Path, config: Path | None, fps: float | None) -> tuple[Any, Any]:
    from mvtrack.analytics import analyse_folder
    from mvtrack.analytics.defaults import choose_settings
    from mvtrack.config import check_fps
    from mvtrack.errors import InputError

    if fps is not None:
        check_fps("--fps", fps)
    if not outdir.is_dir():
        raise InputError(f"{outdir}: no such folder")
    if not (outdir / "results.txt").exists():
        raise InputError(f"{outdir}: no results.txt (run mvtrack track first)")
    chosen = choose_settings(outdir, config)
    typer.echo(f"analytics settings: {chosen.source}")
    return chosen, analyse_folder(outdir, chosen.settings, fps)


def register(app: typer.Typer) -> None:
    """Add the ``analyze`` and ``report`` commands to ``app``."""

    @app.command("analyze")
    def analyze_cmd(
        outdir: Annotated[Path, typer.Argument(help="Output folder with results.txt.")],
        config: Settings = None,
        fps: Fps = None,
    ) -> None:
        """Count, measure movements and speeds of the tracks in OUTDIR/results.txt; write
        counts.csv, movements.csv, speeds.csv, tracks.csv and analytics.json (the settings
        used) into OUTDIR."""
        from mvtrack.analytics.defaults import write_record
        from mvtrack.analytics.outputs import write_outputs

        chosen, result = _run(outdir, config, fps)
        paths = [*write_outputs(result, outdir).values(), write_record(chosen, outdir)]
        for path in paths:
            typer.echo(str(path))

    @app.command("report")
    def report_cmd(
        outdir: Annotated[Path, typer.Argument(help="Output folder with results.txt.")],
        config: Settings = None,
        fps: Fps = None,
    ) -> None:
        """Write OUTDIR/report.html (self-contained), the analytics CSV files and
        analytics.json (the settings used)."""
        from mvtrack.analytics.defaults import write_record
        from mvtrack.analytics.outputs import write_outputs
        from mvtrack.analytics.report import render_report, write_report

        chosen, result = _run(outdir, config, fps)
        render_report(result, outdir)  # every figure is made before any file is written
        paths = [*write_outputs(result, outdir).values(), write_record(chosen, outdir),
                 write_report(result, outdir)]
        for path in paths:
            typer.echo(str(path))
