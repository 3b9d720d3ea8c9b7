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
    Path | None,
    typer.Option(help="TOML settings file; every table and key is in docs/config.md, and "
                 "'mvtrack config --show' prints them all with their defaults."),
]
NoVideo = Annotated[bool, typer.Option("--no-video", help="Skip the annotated MP4 (faster).")]
NoTemplates = Annotated[
    bool, typer.Option("--no-templates", help="No template matching for stopped vehicles.")
]
ScoreHigh = Annotated[
    float | None,
    typer.Option(help="Calibrated score in [0, 1] from which a detection may start a track and "
                 "is matched first; lower ones only extend tracks (ByteTrack's track_thresh; "
                 "default: the preset's).", show_default=False),
]
MinScore = Annotated[
    float | None,
    typer.Option(help="Calibrated score in [0, 1] below which detections are dropped "
                 "(default: the preset's).", show_default=False),
]
Snapshot = Annotated[
    list[int] | None,
    typer.Option(help="Also save the annotated frame N (0-based) as frameNNNNN.png; give it "
                 "again for more frames."),
]
Force = Annotated[
    bool,
    typer.Option("--force", help="Write into an --out folder that holds files mvtrack did not "
                 "write (files of the same names are replaced, the others kept)."),
]

#: what --out means for a command whose folder holds one run
RUN_FOLDER_HELP = (
    "Output folder. It holds this run only: a folder with an earlier run of this command is "
    "replaced when this one finishes (and kept as it was if this one fails); a folder with "
    "anything else is refused unless --force."
)

#: the tracker settings that have an option of their own, by TrackerConfig field
TRACKER_OPTIONS = {
    "preset": "--preset", "predictor": "--predictor", "distance": "--distance",
    "assign": "--assign", "gate": "--gate", "fps": "--fps", "score_high": "--score-high",
    "min_score": "--min-score", "score_scale": "--score-scale",
    "birth_iou": "--birth-iou",
}


def check_choice(option: str, value: str | None, known: object) -> None:
    """Refuse a ``value`` of ``option`` that is not one of ``known`` (one line)."""
    from mvtrack.errors import InputError

    if value is not None and value not in known:  # type: ignore[operator]
        raise InputError(f"{option} {value!r} is not one of: "
                         f"{', '.join(known)}")  # type: ignore[call-overload]


def tracker_names(given: set[str], config: Path | None):  # type: ignore[no-untyped-def]
    """The user's name of each tracker setting: its option when given on the command line,
    else the key of the settings file."""
    def name_of(field: str) -> str:
        if field in given:
            return TRACKER_OPTIONS.get(field, f"--{field.replace('_', '-')}")
        return f"{config}: tracker.{field}" if config is not None else f"tracker.{field}"

    return name_of


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
    score_high: float | None = None,
    min_score: float | None = None,
    fps: float | None = None,
    coasting: bool = False,
) -> RunSettings:
    """The :class:`~mvtrack.config.RunSettings` the command-line options ask for.

    The TOML file (if any) first, then each option that was given on top of it. Every value
    is checked here, before any work: the tracker is built once (at the run's frame rate if
    one is given), and a message names the option or the file's key that is wrong.

    Raises
    ------
    InputError
        A bad settings file, an unknown detector, predictor, distance or assignment rule, a
        bad gate, score or frame rate (one line).
    """
    from mvtrack.config import RunSettings, check_fps, check_tracker, load_config
    from mvtrack.errors import InputError

    settings = load_config(config) if config is not None else RunSettings()
    check_choice("--preset", preset, _presets())
    check_choice("--predictor", predictor, PREDICTORS)
    check_choice("--distance", distance, DISTANCES)
    check_choice("--assign", assign, ASSIGN_RULES)
    if fps is not None:
        check_fps("--fps", fps)
    options = {"preset": preset, "predictor": predictor, "gate": parse_gate(gate),
               "distance": distance, "assign": assign, "score_high": score_high,
               "min_score": min_score, "fps": fps}
    given = {k for k, v in options.items() if v is not None}
    settings = settings.with_overrides(**options)
    if given:
        check_tracker(settings.tracker, tracker_names(given, config))
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
    if settings.detector_params or settings.template_params:
        _check_parts(settings, config)
    if no_video:
        settings = dataclasses.replace(settings, video=False)
    if no_templates:
        settings = dataclasses.replace(settings, templates=False)
    if coasting:
        settings = dataclasses.replace(settings, coasting=True)
    return settings


def _presets() -> tuple[str, ...]:
    from mvtrack.tracking import PRESETS

    return tuple(PRESETS)


def _check_parts(settings: RunSettings, config: Path | None) -> None:
    """Build the detector, tracker and template bank of ``settings`` once (at the papers'
    image size), so a bad parameter of the file stops the command before any work."""
    from mvtrack.errors import InputError
    from mvtrack.video import check_settings

    try:
        check_settings(settings, settings.frame_rate or 30.0)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{config}: {exc}") from None


def speed_note() -> str:
    """``; this first run includes compiling the kernels`` after a speed measured in a
    process that compiled them (:func:`mvtrack.jit.compiled_here`), else nothing."""
    from mvtrack.jit import compiled_here

    return "; this first run includes compiling the kernels" if compiled_here() else ""
