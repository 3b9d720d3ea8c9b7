"""Options shared by the commands that run the video pipeline (``track``, ``batch``) and the
tracker (``track-detections``), and how they become settings.

Each alias below is one option, so the commands spell, document and check it the same way.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from mvtrack.registry import (
    ASSIGN_RULES,
    DEFAULT_DETECTOR,
    DETECTORS,
    DISTANCES,
    PREDICTORS,
    gate_help,
    one_of,
)

if TYPE_CHECKING:
    from mvtrack.config import RunSettings

#: the --gate help, with every distance's default gate (from mvtrack.registry.DISTANCES)
GATE_HELP = gate_help()

Preset = Annotated[str | None, typer.Option(help="Tracker preset: default, paper1, paper2.")]
Predictor = Annotated[str | None, typer.Option(help=f"{one_of(PREDICTORS)}.")]
Distance = Annotated[str | None, typer.Option(help=f"{one_of(DISTANCES)}.")]
Assign = Annotated[str | None, typer.Option(help=f"{one_of(ASSIGN_RULES)}.")]
Gate = Annotated[str | None, typer.Option(help=GATE_HELP)]
DetectorName = Annotated[
    str | None, typer.Option(help=f"{one_of(DETECTORS, DEFAULT_DETECTOR)}.")
]
ConfigFile = Annotated[
    Path | None, typer.Option(help="TOML settings file (see mvtrack.config).")
]
NoVideo = Annotated[bool, typer.Option("--no-video", help="Skip the annotated MP4 (faster).")]
NoTemplates = Annotated[
    bool, typer.Option("--no-templates", help="No template matching for stopped vehicles.")
]


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


def parse_optional_number(option: str, text: str) -> float | None:
    """``"0.1"`` → 0.1, ``"none"`` → None (the setting off); anything else is an error."""
    raw = text.strip().lower()
    if raw == "none":
        return None
    try:
        return float(raw)
    except ValueError:
        raise ValueError(f"{option} must be a number or 'none', got {text!r}") from None


def video_settings(
    *,
    config: Path | None,
    preset: str | None,
    predictor: str | None,
    gate: str | None,
    distance: str | None,
    assign: str | None,
    detector: str | None,
    no_video: bool,
    no_templates: bool,
) -> RunSettings:
    """The :class:`~mvtrack.config.RunSettings` the command-line options ask for.

    The TOML file (if any) first, then each option that was given on top of it.

    Raises
    ------
    InputError
        A bad settings file, an unknown detector or a bad gate (one line).
    """
    from mvtrack.config import RunSettings, load_config
    from mvtrack.errors import InputError

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
        if detector != settings.detector and settings.detector_params:
            keys = ", ".join(sorted(settings.detector_params))
            raise InputError(
                f"--detector {detector!r} replaces the config's detector "
                f"{settings.detector!r}, whose parameters ({keys}) would not apply: set "
                f"[detector] name = {detector!r} in {config} instead"
            )
        settings = dataclasses.replace(settings, detector=detector,
                                       detector_params=settings.detector_params)
    if no_video:
        settings = dataclasses.replace(settings, video=False)
    if no_templates:
        settings = dataclasses.replace(settings, templates=False)
    return settings
