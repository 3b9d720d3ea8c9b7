"""``mvtrack experiment NAME``: reproduce a figure or table of the papers."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from mvtrack import experiments


def register(app: typer.Typer) -> None:
    """Add the ``experiment`` command to ``app``."""

    @app.command("experiment")
    def experiment_cmd(
        name: Annotated[str, typer.Argument(help=f"One of: {', '.join(experiments.EXPERIMENTS)}")],
        runs: Annotated[
            int | None, typer.Option(help="Monte-Carlo runs or seeds (default: the paper's).")
        ] = None,
        seed: Annotated[int, typer.Option(help="Seed of the first run.")] = 0,
        out: Annotated[Path, typer.Option(help="Folder for NAME.json, NAME.md and plots.")] = Path(
            "results"
        ),
    ) -> None:
        """Run experiment NAME and write NAME.json, NAME.md and its PNG plots into --out."""
        from mvtrack.experiments.report import write_report

        if runs is not None and runs < 1:
            raise ValueError(f"--runs must be at least 1, got {runs}")
        run = experiments.get(name)
        report = run(runs=runs, seed=seed)
        for path in write_report(report, out):
            typer.echo(str(path))
