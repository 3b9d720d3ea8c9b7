"""``mvtrack track-detections``: run the tracker on a MOTChallenge detection file."""

from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add this module's commands to ``app``."""
