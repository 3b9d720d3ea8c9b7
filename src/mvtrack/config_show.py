"""Every setting with its default, as a TOML file to edit (``mvtrack config --show``).

Nothing here is a second copy of a default: the ``[tracker]`` table is the named preset
(:func:`mvtrack.tracking.preset`, every field of ``TrackerConfig`` in its order, with the first
sentence of the field's description as a comment), the detector's and the template bank's
parameters are read from their constructors' signatures, ``[video]`` and ``[relink]`` from
:class:`~mvtrack.config.RunSettings` and :class:`~mvtrack.config.RelinkSettings`. What the
video pipeline sets for each video from its size (:func:`mvtrack.video.resolve_settings`) is
found by resolving the empty settings at two image sizes; those keys, the frame rate and the
front end's parameters are written commented out, so the file as printed changes nothing:
``mvtrack track VIDEO --config FILE`` tracks exactly as without it.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import re
import textwrap
from collections.abc import Callable, Mapping
from typing import Any

#: the image sizes at which the per-video values are shown (the papers' and vtest.avi's)
SIZES = ((320, 240), (768, 576))
_WIDTH = 96


def toml_value(value: Any) -> str:
    """``value`` written as TOML (``None`` as ``"none"``, which the settings file reads as
    None)."""
    if value is None:
        return '"none"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(int(value))
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return repr(value) if math.isfinite(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, Mapping):
        inner = ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items())
        return "{ " + inner + " }" if inner else "{}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return json.dumps(str(value))


def _plain(text: str) -> str:
    """numpydoc / reST markup as plain text: a module by its full name, anything else by its
    own (``:mod:`mvtrack.association.gate``` is mvtrack.association.gate, ``:func:`~a.b``` b)."""
    text = re.sub(r":(\w+):`~?([^`]+)`",
                  lambda m: m.group(2) if m.group(1) == "mod" else m.group(2).rsplit(".", 1)[-1],
                  text)
    return text.replace("``", "")


def field_notes(cls: type) -> dict[str, str]:
    """The first sentence of each attribute's description in ``cls``'s numpydoc docstring."""
    doc = inspect.getdoc(cls) or ""
    notes: dict[str, str] = {}
    name, lines = None, []
    for line in doc.splitlines():
        head = re.fullmatch(r"(\w+) : .*", line)
        if head or (line and not line.startswith(" ")):
            if name is not None:
                notes[name] = _first_sentence(" ".join(lines))
            name, lines = (head.group(1), []) if head else (None, [])
        elif name is not None:
            lines.append(line.strip())
    if name is not None:
        notes[name] = _first_sentence(" ".join(lines))
    return notes


def _first_sentence(text: str, least: int = 40) -> str:
    """The first sentence of ``text``, and the next ones while it is shorter than ``least``
    characters ("Pixels." says little alone)."""
    text = _plain(" ".join(text.split()))
    end = 0
    for m in re.finditer(r"(?<!\b\w)\.(\s|$)", text):  # not the dot of "e.g."
        end = m.start() + 1
        if end >= least:
            break
    else:
        end = len(text)
    return text[:end]


def _comment(text: str) -> list[str]:
    return textwrap.wrap(text, _WIDTH - 2, initial_indent="# ", subsequent_indent="# ")


def _resolved(preset: str, detector: str) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """The tracker and detector values the video pipeline sets, at each of :data:`SIZES`."""
    from mvtrack.config import RunSettings
    from mvtrack.video import resolve_settings

    empty = RunSettings(tracker={"preset": preset}, detector=detector)
    out = []
    for size in SIZES:
        r = resolve_settings(empty, size)
        tracker = {k: v for k, v in r.tracker.items() if k != "preset"}
        out.append((tracker, dict(r.detector_params)))
    return out


def _shifts(preset: str, detector: str, key: str, value: Any) -> bool:
    """Whether giving ``key = value`` changes the tracker the video pipeline builds for some
    image size (a key whose presence stops another value from being set per video)."""
    from mvtrack.config import RunSettings
    from mvtrack.video import build_tracker_config, resolve_settings

    empty = RunSettings(tracker={"preset": preset}, detector=detector)
    given = RunSettings(tracker={"preset": preset, key: value}, detector=detector)
    return any(build_tracker_config(resolve_settings(empty, size), 30.0)
               != build_tracker_config(resolve_settings(given, size), 30.0) for size in SIZES)


def _per_video(key: str, values: list[dict[str, Any]]) -> str:
    shown = [f"{toml_value(v[key])} at {w}×{h}" for v, (w, h) in zip(values, SIZES, strict=True)
             if key in v]
    if len(shown) == len(values) and len({toml_value(v[key]) for v in values}) == 1:
        return f"mvtrack track sets it for each video ({shown[0]})"
    return f"mvtrack track sets it for each video from its size ({', '.join(shown)})"


def _signature_defaults(targets: list[Callable[..., Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for target in targets:
        for p in inspect.signature(target).parameters.values():
            if p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL) or p.default is p.empty:
                continue
            out.setdefault(p.name, p.default)
    return out


def default_toml(preset: str = "default", detector: str | None = None) -> str:
    """The settings file with every key at its default for tracker ``preset`` and front end
    ``detector`` (default: :data:`mvtrack.registry.DEFAULT_DETECTOR`).

    Raises
    ------
    InputError
        An unknown preset or detector.
    """
    from mvtrack.config import (
        RelinkSettings,
        RunSettings,
        detector_signatures,
        template_signatures,
    )
    from mvtrack.errors import InputError
    from mvtrack.registry import DEFAULT_DETECTOR, DETECTORS
    from mvtrack.tracking import PRESETS, TrackerConfig
    from mvtrack.tracking import preset as make_preset

    detector = DEFAULT_DETECTOR if detector is None else detector
    if preset not in PRESETS:
        raise InputError(f"--preset {preset!r} is not a tracker preset (choose one of: "
                         f"{', '.join(PRESETS)})")
    if detector not in DETECTORS:
        raise InputError(f"--detector {detector!r} is not a detector (choose one of: "
                         f"{', '.join(DETECTORS)})")
    config = make_preset(preset)
    resolved = _resolved(preset, detector)
    tracker_video = [t for t, _ in resolved]
    detector_video = [d for _, d in resolved]
    notes = field_notes(TrackerConfig)
    lines = [
        f"# mvtrack settings: every key at its default (tracker preset {preset!r}, detector "
        f"{detector!r}).",
        "# Made by `mvtrack config --show`; read by `mvtrack track VIDEO --config FILE` and",
        "# `mvtrack batch` (every table) and `mvtrack track-detections` ([tracker] only).",
        "# Every key is optional, and options on the command line win over the file. A line",
        "# '# key = value' is set for each run (from the video's size, frame rate or front",
        "# end) unless you give it: uncomment it to fix its value. TOML has no null: \"none\"",
        "# turns a setting off. What each table means: docs/config.md.",
        "",
        "[tracker]",
        f"preset = {toml_value(preset)}",
    ]
    for f in dataclasses.fields(TrackerConfig):
        value = getattr(config, f.name)
        lines.append("")
        lines.extend(_comment(notes.get(f.name, "")))
        text = f"{f.name} = {toml_value(value)}"
        if f.name == "fps":
            lines.append(f"# {text}  (the source's frame rate unless given here or by --fps)")
        elif any(f.name in t for t in tracker_video):
            lines.append(f"# {f.name} = {toml_value(tracker_video[0].get(f.name, value))}")
            lines.extend(_comment(_per_video(f.name, tracker_video)
                                  + f"; mvtrack track-detections: {toml_value(value)}"))
        elif _shifts(preset, detector, f.name, value):
            lines.append(f"# {text}")
            lines.extend(_comment("given, it keeps mvtrack track from setting other values "
                                  "of this table for each video"))
        else:
            lines.append(text)

    settings = RunSettings()
    lines += ["", "[detector]", f"name = {toml_value(detector)}",
              "# the front end's parameters (uncomment to change):"]
    params = _signature_defaults(detector_signatures(detector))
    for key in sorted(set().union(*detector_video)):
        params.setdefault(key, detector_video[0][key])
    for key, value in params.items():
        if any(key in d for d in detector_video):
            lines.append(f"# {key} = {toml_value(detector_video[0].get(key, value))}  "
                         f"({_per_video(key, detector_video)})")
        else:
            lines.append(f"# {key} = {toml_value(value)}")

    lines += ["", "[templates]", f"enabled = {toml_value(settings.templates)}",
              "# the template bank's parameters (uncomment to change):"]
    for key, value in _signature_defaults(template_signatures()).items():
        lines.append(f"# {key} = {toml_value(value)}")
    lines.append("# (min_pixels is set from the front end's min_area unless given; max_shift "
                 "from the rescuer)")

    lines += ["", "[video]", f"write = {toml_value(settings.video)}",
              f"trail = {toml_value(settings.trail)}", f"gates = {toml_value(settings.gates)}"]

    relink = RelinkSettings()
    relink_notes = field_notes(RelinkSettings)
    lines += ["", "[relink]"]
    for f in dataclasses.fields(RelinkSettings):
        lines.extend(_comment(relink_notes.get(f.name, "")))
        lines.append(f"{f.name} = {toml_value(getattr(relink, f.name))}")

    lines += ["", "# [analytics]  counts on lines, zones, turning movements and speeds: see",
              "# docs/analytics-example.toml", ""]
    return "\n".join(lines)
