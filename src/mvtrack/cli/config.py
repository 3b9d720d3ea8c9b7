"""``mvtrack config``: the settings file — every key with its default, or a file checked."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated

import typer

from mvtrack.registry import DEFAULT_DETECTOR, DETECTORS, one_of


def register(app: typer.Typer) -> None:
    """Add the ``config`` command to ``app``."""

    @app.command("config")
    def config_cmd(
        show: Annotated[
            bool,
            typer.Option("--show", help="Print every setting with its default as a TOML file "
                         "to edit: mvtrack config --show > scene.toml."),
        ] = False,
        check: Annotated[
            Path | None,
            typer.Option("--check", help="Check a settings file as mvtrack track would read it "
                         "(one line naming a bad key), and print the tracker it gives.",
                         metavar="FILE"),
        ] = None,
        preset: Annotated[
            str, typer.Option(help="With --show: the tracker preset (default, paper1, paper2).")
        ] = "default",
        detector: Annotated[
            str | None,
            typer.Option(help="With --show: the front end "
                         f"({one_of(DETECTORS, DEFAULT_DETECTOR)})."),
        ] = None,
    ) -> None:
        """The settings file of --config (docs/config.md): --show prints every key with its
        default, ready to edit; --check FILE reads a file as mvtrack track does."""
        from mvtrack.errors import InputError

        if show == (check is not None):
            raise InputError("give --show (print the defaults) or --check FILE")
        if show:
            from mvtrack.config_show import default_toml

            typer.echo(default_toml(preset, detector), nl=False)
            return
        from mvtrack.config import load_config
        from mvtrack.video import build_tracker_config

        assert check is not None
        settings = load_config(check)
        config = build_tracker_config(settings, settings.frame_rate or 30.0)
        typer.echo(f"{check}: valid; detector {settings.detector!r}, tracker:")
        for f in dataclasses.fields(config):
            typer.echo(f"  {f.name} = {getattr(config, f.name)!r}")
