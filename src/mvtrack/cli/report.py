"""``mvtrack analyze OUTDIR`` and ``mvtrack report OUTDIR``: traffic analytics on an existing
output folder (``results.txt`` of ``mvtrack track``, plus a TOML settings file)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

Settings = Annotated[
    Path | None,
    typer.Option("--config", help="TOML file with an [analytics] table (lines, zones, "
                 "approaches, calibration, interval); see docs/analytics-example.toml."),
]
Fps = Annotated[float | None, typer.Option(help="Frame rate (default: summary.json).")]


def _run(outdir: Path, config: Path | None, fps: float | None):  # type: ignore[no-untyped-def]
    from mvtrack.analytics import AnalyticsSettings, analyse_folder, load_settings

    if fps is not None and not fps > 0:
        raise ValueError(f"--fps must be positive, got {fps}")
    settings = load_settings(config) if config is not None else AnalyticsSettings()
    return analyse_folder(outdir, settings, fps)


def register(app: typer.Typer) -> None:
    """Add the ``analyze`` and ``report`` commands to ``app``."""

    @app.command("analyze")
    def analyze_cmd(
        outdir: Annotated[Path, typer.Argument(help="Output folder with results.txt.")],
        config: Settings = None,
        fps: Fps = None,
    ) -> None:
        """Count, measure movements and speeds of the tracks in OUTDIR/results.txt; write
        counts.csv, movements.csv, speeds.csv and tracks.csv into OUTDIR."""
        from mvtrack.analytics.outputs import write_outputs

        result = _run(outdir, config, fps)
        for path in write_outputs(result, outdir).values():
            typer.echo(str(path))

    @app.command("report")
    def report_cmd(
        outdir: Annotated[Path, typer.Argument(help="Output folder with results.txt.")],
        config: Settings = None,
        fps: Fps = None,
    ) -> None:
        """Write OUTDIR/report.html (self-contained) and the analytics CSV files."""
        from mvtrack.analytics.outputs import write_outputs
        from mvtrack.analytics.report import write_report

        result = _run(outdir, config, fps)
        for path in write_outputs(result, outdir).values():
            typer.echo(str(path))
        typer.echo(str(write_report(result, outdir)))
